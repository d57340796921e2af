#pragma once
// What the AVX2 and AVX-512 evaluation kernels share (internal; see fast_kernel.hpp): prefetches
// and stores (streaming for rows in order, 12 bytes a row scattered). Functions compiled for
// AVX2/FMA by their target attribute, as the kernels are, so that nothing here is built for a
// CPU the caller did not check.
#include "evaluate/fast_kernel.hpp"

#ifdef MBI_INTERP_X86
#include <cstdint>

#define MBI_TARGET_AVX2 __attribute__((target("avx2,fma")))
#define MBI_TARGET_AVX512 __attribute__((target("avx512f,avx512dq,avx512vl,avx2,fma")))

namespace mbi::interp::detail {

// The input streams (records, rest normals) are prefetched this many points ahead: the hardware
// prefetcher alone falls behind once the element terms' L2 traffic runs alongside.
constexpr int kStreamAhead = 128;

// Prefetch the byte at p + bytes: integer arithmetic, so that an address past the end of a buffer
// is never formed as a pointer (a prefetch does not fault).
inline void prefetch_at(const void* p, long long bytes) {
  _mm_prefetch(reinterpret_cast<const char*>(reinterpret_cast<std::uintptr_t>(p) + static_cast<std::uintptr_t>(bytes)),
               _MM_HINT_T0);
}

// Prefetch the element terms (both lines) of the 4 points kPrefetch after p (records are padded:
// those are always records; their element may lie outside a block of terms, hence prefetch_at).
MBI_TARGET_AVX2 inline void prefetch_terms(const std::int32_t* rec, const float* coef, std::int32_t ebase, long long p) {
  for (int k = 0; k < 4; ++k) {
    const long long at = (static_cast<long long>(rec[4 * (p + k + kPrefetch)]) - ebase) * coef_stride(3) * 4;
    prefetch_at(coef, at);
    prefetch_at(coef, at + 64);
  }
}

// Prefetch the output rows (in pos and, when set, nout) of the 4 points kRowAhead after p, for
// writing (the permutation is padded: those are always rows).
MBI_TARGET_AVX2 inline void prefetch_rows(const std::int32_t* row, float* pos, float* nout, long long p) {
  for (int k = 0; k < 4; ++k) {
    const long long r = 3LL * row[p + k + kRowAhead];
    _mm_prefetch(reinterpret_cast<const char*>(pos + r), _MM_HINT_T0);
    if (nout) _mm_prefetch(reinterpret_cast<const char*>(nout + r), _MM_HINT_T0);
  }
}

// A point's coordinates (lanes 0-2 of v) to its row at out: 8 + 4 bytes, nothing past the row
// (the next row may be another thread's).
MBI_TARGET_AVX2 inline void store3(float* out, __m128 v) {
  _mm_storel_pi(reinterpret_cast<__m64*>(out), v);
  _mm_store_ss(out + 2, _mm_movehl_ps(v, v));
}

// 4 points' vectors (x, y, z, .) to their rows out + 3 row[k].
MBI_TARGET_AVX2 inline void scatter4(float* out, const std::int32_t* row, __m128 r0, __m128 r1, __m128 r2, __m128 r3) {
  store3(out + 3LL * row[0], r0);
  store3(out + 3LL * row[1], r1);
  store3(out + 3LL * row[2], r2);
  store3(out + 3LL * row[3], r3);
}

// 12 floats to out: streaming when out is 16-byte aligned.
MBI_TARGET_AVX2 inline void store12(float* out, bool aligned, __m128 o0, __m128 o1, __m128 o2) {
  if (aligned) {
    _mm_stream_ps(out, o0);
    _mm_stream_ps(out + 4, o1);
    _mm_stream_ps(out + 8, o2);
  } else {
    _mm_storeu_ps(out, o0);
    _mm_storeu_ps(out + 4, o1);
    _mm_storeu_ps(out + 8, o2);
  }
}

}  // namespace mbi::interp::detail
#endif
