// interp::evaluate<float>'s positions in 3D (internal): FastEvaluator's kernels run on the
// Embedding as it is, with no set-up per embedding. Per call the element terms are written once
// (as FastEvaluator does); then per block of kChunk points the points' records are packed into a
// buffer that stays in L1, the kernel writes the block's positions beside it (plain stores: the
// buffer is read back at once), and they are copied into the output's three columns.
#include "evaluate/evaluate_float.hpp"

#include "evaluate/fast_kernel.hpp"
#include "runtime/threads.hpp"

#include <mbi/error.hpp>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <string>
#include <vector>

namespace mbi::interp::detail {
namespace {

constexpr long long kChunk = 512;      // points packed at a time (8 KiB of records, 6 KiB out)
constexpr long long kShare = 8 * kChunk;  // points a thread takes at a time

std::int32_t as_word(float f) {
  std::int32_t w;
  std::memcpy(&w, &f, sizeof w);
  return w;
}

// Records of points [b, b + n): element id, then b_1..b_3 as float bit patterns; returns how many
// points follow a point of the same element, or -1 when an element id is not in [0, m).
long long pack_plain(const int* el, const double* b1, const double* b2, const double* b3, long long b, long long n,
                     int m, std::int32_t* rec) {
  long long same = 0;
  for (long long i = 0; i < n; ++i) {
    if (el[b + i] < 0 || el[b + i] >= m) return -1;
    rec[4 * i] = el[b + i];
    rec[4 * i + 1] = as_word(static_cast<float>(b1[b + i]));
    rec[4 * i + 2] = as_word(static_cast<float>(b2[b + i]));
    rec[4 * i + 3] = as_word(static_cast<float>(b3[b + i]));
    same += i > 0 && el[b + i] == el[b + i - 1];
  }
  return same;
}

// The positions of [b, b + n) from xyz (interleaved) into the three columns.
void unpack_plain(const float* xyz, long long b, long long n, float* px, float* py, float* pz) {
  for (long long i = 0; i < n; ++i) {
    px[b + i] = xyz[3 * i];
    py[b + i] = xyz[3 * i + 1];
    pz[b + i] = xyz[3 * i + 2];
  }
}

#ifdef MBI_INTERP_X86
// 4 points at a time: the four columns converted and transposed into 4 records.
__attribute__((target("avx2,fma"))) long long pack_avx2(const int* el, const double* b1, const double* b2,
                                                        const double* b3, long long b, long long n, int m,
                                                        std::int32_t* rec) {
  long long i = 0, same = 0;
  const __m128i lo = _mm_set1_epi32(-1), hi = _mm_set1_epi32(m);
  __m128i bad = _mm_setzero_si128();
  for (; i + 4 <= n; i += 4) {
    const __m128i ei = _mm_loadu_si128(reinterpret_cast<const __m128i*>(el + b + i));
    bad = _mm_or_si128(bad, _mm_or_si128(_mm_cmpgt_epi32(lo, ei), _mm_cmpgt_epi32(hi, ei) ^ _mm_set1_epi32(-1)));
    __m128 e = _mm_castsi128_ps(ei);
    __m128 x = _mm256_cvtpd_ps(_mm256_loadu_pd(b1 + b + i));
    __m128 y = _mm256_cvtpd_ps(_mm256_loadu_pd(b2 + b + i));
    __m128 z = _mm256_cvtpd_ps(_mm256_loadu_pd(b3 + b + i));
    _MM_TRANSPOSE4_PS(e, x, y, z);
    float* r = reinterpret_cast<float*>(rec + 4 * i);
    _mm_store_ps(r, e);
    _mm_store_ps(r + 4, x);
    _mm_store_ps(r + 8, y);
    _mm_store_ps(r + 12, z);
  }
  if (!_mm_testz_si128(bad, bad)) return -1;
  const long long tail = pack_plain(el, b1, b2, b3, b + i, n - i, m, rec + 4 * i);
  if (tail < 0) return -1;
  for (long long k = 1; k < i; ++k) same += el[b + k] == el[b + k - 1];
  return same + tail + (i > 0 && i < n && el[b + i] == el[b + i - 1]);
}

// 4 points at a time: 12 interleaved floats transposed into x, y and z, streamed out (not read
// into the cache first) when the three columns are 16-byte aligned there.
__attribute__((target("avx2,fma"))) void unpack_avx2(const float* xyz, long long b, long long n, float* px,
                                                     float* py, float* pz) {
  const bool aligned =
      ((reinterpret_cast<std::uintptr_t>(px + b) | reinterpret_cast<std::uintptr_t>(py + b) |
        reinterpret_cast<std::uintptr_t>(pz + b)) & 15) == 0;
  long long i = 0;
  for (; i + 4 <= n; i += 4) {
    const __m128 a = _mm_loadu_ps(xyz + 3 * i);      // x0 y0 z0 x1
    const __m128 c = _mm_loadu_ps(xyz + 3 * i + 4);  // y1 z1 x2 y2
    const __m128 d = _mm_loadu_ps(xyz + 3 * i + 8);  // z2 x3 y3 z3
    // each column: its 4 values blended into place from a, c and d, then put in order
    const __m128 tx = _mm_blend_ps(_mm_blend_ps(a, c, 0x4), d, 0x2);  // x0 x3 x2 x1
    const __m128 ty = _mm_blend_ps(_mm_blend_ps(a, c, 0x9), d, 0x4);  // y1 y0 y3 y2
    const __m128 tz = _mm_blend_ps(_mm_blend_ps(a, c, 0x2), d, 0x9);  // z2 z1 z0 z3
    const __m128 x = _mm_shuffle_ps(tx, tx, _MM_SHUFFLE(1, 2, 3, 0));
    const __m128 y = _mm_shuffle_ps(ty, ty, _MM_SHUFFLE(2, 3, 0, 1));
    const __m128 z = _mm_shuffle_ps(tz, tz, _MM_SHUFFLE(3, 0, 1, 2));
    if (aligned) {
      _mm_stream_ps(px + b + i, x);
      _mm_stream_ps(py + b + i, y);
      _mm_stream_ps(pz + b + i, z);
    } else {
      _mm_storeu_ps(px + b + i, x);
      _mm_storeu_ps(py + b + i, y);
      _mm_storeu_ps(pz + b + i, z);
    }
  }
  unpack_plain(xyz + 3 * i, b + i, n - i, px, py, pz);
}
#endif

// The kernel for positions, with or without prefetches of the element terms (points in random
// order need them, points in a mesh's order do not).
Kernel kernel(bool prefetch) {
#ifdef MBI_INTERP_X86
  if (have_avx512()) return avx512_kernels[0][prefetch ? 1 : 0][0];
  if (have_avx2_fma()) return avx2_kernels[0][prefetch ? 1 : 0][0];
#endif
  (void)prefetch;
  return nullptr;
}

}  // namespace

void evaluate_float3(const MatrixIn& B, const Embedding& emb, PointsRef<float> positions, int threads) {
  const long long p = emb.size();
  const int m = static_cast<int>(B.rows() / 10);
  if (p == 0) return;
  // the element terms: scratch of the calling thread, kept between calls
  thread_local std::vector<float> terms;
  terms.resize(std::max(terms.size(), static_cast<size_t>(m) * coef_stride(3) + 16));
  float* coef = reinterpret_cast<float*>((reinterpret_cast<std::uintptr_t>(terms.data()) + 63) & ~std::uintptr_t(63));
  pairs_terms3(B, coef, m, thread_count(m, 512, threads));
  const int* el = emb.element.data();
  const double* b1 = emb.bary.data() + p;  // column-major: columns 1, 2, 3
  const double* b2 = b1 + p;
  const double* b3 = b2 + p;
  float* px = positions.data();  // columns outerStride() apart
  float* py = px + positions.outerStride();
  float* pz = py + positions.outerStride();
  // the x86 kernels come with AVX2 (and AVX-512 with both): pack and unpack with AVX2 then
  bool simd = false;
  auto pack_x86 = pack_plain;
  auto unpack_x86 = unpack_plain;
#ifdef MBI_INTERP_X86
  simd = have_avx2_fma();
  pack_x86 = pack_avx2;
  unpack_x86 = unpack_avx2;
#endif
  std::atomic<bool> bad{false};
  Blocks share(p, kShare);
  run_shared(thread_count(p, kShare, threads), [&] {
    // records, then kPrefetch more for the kernel's prefetches past the end (element 0 or a
    // previous chunk's: any element of the mesh); positions one float past a 16-byte boundary,
    // so that the kernel stores them plainly (into the cache) instead of streaming them out
    alignas(64) std::int32_t rec[(kChunk + kPrefetch) * 4] = {};
    alignas(64) float out[kChunk * 3 + 4];
    float* xyz = out + 1;
    for (long long s0, s1; share.next(s0, s1);)
      for (long long b = s0; b < s1; b += kChunk) {
        const long long n = b + kChunk < s1 ? kChunk : s1 - b;
        const long long same = simd ? pack_x86(el, b1, b2, b3, b, n, m, rec) : pack_plain(el, b1, b2, b3, b, n, m, rec);
        if (same < 0) {  // an element out of range: the first such point is named below
          bad = true;
          continue;
        }
        long long done = 0;
        if (const Kernel k = kernel(2 * same < n)) {
          done = n / 4 * 4;
          k(rec, coef, 0, nullptr, 1.0f, xyz, nullptr, nullptr, 0, done);
        }
        eval_portable(3, rec, coef, 0, kPairs, nullptr, 1.0f, xyz, nullptr, nullptr, done, n);
        if (simd) unpack_x86(xyz, b, n, px, py, pz);
        else unpack_plain(xyz, b, n, px, py, pz);
      }
#ifdef MBI_INTERP_X86
    _mm_sfence();  // the streamed stores reach memory before the caller reads them
#endif
  });
  if (bad)
    for (long long i = 0; i < p; ++i)
      if (el[i] < 0 || el[i] >= m)
        throw Error("point " + std::to_string(i) + " refers to element " + std::to_string(el[i]) +
                    " outside [0, " + std::to_string(m) + ")");
}

}  // namespace mbi::interp::detail
