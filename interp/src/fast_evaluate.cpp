// The compact float evaluation kernel (see fast_evaluate.hpp).
//
// Each element's quadratic Bezier simplex sum_k b_k^2 P_k + sum_{i<j} 2 b_i b_j P_ij is rewritten,
// with b_0 = 1 - b_1 - ... - b_d, as a polynomial in (b_1..b_d):
//   x = c_0 + sum_k b_k c_k + sum_{k<=l} b_k b_l c_kl
//   c_0 = P_0, c_k = 2 (P_0k - P_0), c_kk = P_0 + P_k - 2 P_0k,
//   c_kl = 2 (P_0 - P_0k - P_0l + P_kl) (k < l),
// evaluated as x = (c_0 + b_1 t_1) + (b_2 t_2 + ... + b_d t_d), t_k = c_k + sum_{l>=k} b_l c_kl
// (every kernel sums in this order): in 3D 10 multiply-adds on (x, y, z, *) vectors a point. The
// kernels (Simd): AVX2 puts one point and two terms in a 256-bit vector for positions (the
// "pairs" layout below) and two points with normals (the "packed" layout); AVX-512 puts two
// points, each as in the AVX2 positions kernel, in a 512-bit vector, with and without normals
// (pairs layout); the portable loop reads either layout.
//
// Normals need no second table. With D_k = dx/db_k = c_k + sum_l e_kl b_l (e_kl = c_kl for
// k != l, 2 c_kk for k = l; from the t_k above, 6 more FMAs in 3D) and A the matrix whose columns
// are the gradients a_k of b_k over the rest space, the Jacobian is J = D A^T, so
//   cof(J) n = cof(D) cof(A)^T n = cof(D) m,   m = cof(A)^T n   (fact 6; cof(XY) = cof(X) cof(Y)).
// m depends on the rest state only: set_rest_normals() stores it per point (in double, rounded
// once) in place of n, and a point's normal is cof(D) m = m_1 (D_2 x D_3) + m_2 (D_3 x D_1) +
// m_3 (D_1 x D_2), renormalised (the AVX-512 kernel: the same vector as
// D_2 x (m_1 D_3 - m_3 D_1) + m_2 (D_3 x D_1), two cross products instead of three).
//
// The coefficients are computed in double from B and rounded to float once per call.
#include <mbi/interp/fast_evaluate.hpp>

#include "cpu.hpp"

#include "detail.hpp"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <string>

#ifdef _OPENMP
#include <omp.h>
#define MBI_OMP(x) _Pragma(x)
#else
#define MBI_OMP(x)
#endif

#if (defined(__x86_64__) || defined(__i386__)) && (defined(__GNUC__) || defined(__clang__))
#define MBI_FAST_X86 1
#include <immintrin.h>
#endif

namespace mbi::interp {
namespace {

// Per element, the position polynomial's terms (d floats each) padded to whole cache lines (3D:
// 10 x 3 = 30 floats in 32, 128 B: 2 lines, 64-byte aligned), in one of two layouts (Layout).
constexpr int position_terms(int d) { return 1 + d * (d + 3) / 2; }  // 10 in 3D, 6 in 2D
constexpr int coef_stride(int d) { return d == 3 ? 32 : 16; }
static_assert(position_terms(3) * 3 + 1 <= coef_stride(3) && position_terms(2) * 2 <= coef_stride(2));

// Records past the last point (element 0): the x86 kernel prefetches the coefficients of the
// point kPrefetch ahead without a bounds check.
constexpr int kPrefetch = 16;

// The input streams (records, rest normals) are prefetched this many points ahead by the x86
// kernel: the hardware prefetcher alone fell behind once the element terms' L2 traffic ran
// alongside (measured: 1M random points, 2 threads, 1.85 -> 1.55 ms).
constexpr int kStreamAhead = 128;

// Points a thread takes at a time (a multiple of 16); also the fewest points a thread is given.
constexpr long long kBlock = 32768;
static_assert(kBlock % 4 == 0, "blocks must keep each thread's first output float 16-byte aligned");
static_assert(kBlock % 16 == 0, "the AVX-512 kernel's 16-point groups of rest normals (set_rest_normals) "
                                "must start at each block's first point");

// Index of c_k (lin) and c_kl, k <= l (quad), 1-based k, l, in an element's terms (c_0 is term 0).
// 3D: 0 c0, 1 c1, 2 c11, 3 c12, 4 c13, 5 c2, 6 c22, 7 c23, 8 c3, 9 c33.
struct TermIndex {
  int lin[4] = {}, quad[4][4] = {};
  constexpr explicit TermIndex(int d) {
    int s = 1;
    for (int k = 1; k <= d; ++k) {
      lin[k] = s++;
      for (int l = k; l <= d; ++l, ++s) quad[k][l] = quad[l][k] = s;
    }
  }
};

// Where component c of term t lies in an element's coef_stride(d) floats: off[t] + c stride[t].
//  packed (normals calls, and 2D): term t at d t, its components side by side;
//  pairs (3D positions-only calls): eight 16-byte slots, two to a 32-byte vector, read by the
//   x86 kernel with 4 aligned 256-bit loads: (c1 | c2), (c11 | c22), (c12 | c23), (c13 | c33),
//   each slot's 4th float holding one component of c0 or c3: slots 0, 2, 4 c0 x, y, z, slots 1,
//   3, 5 c3 x, y, z (stride 8); slots 6 and 7 end in 0.
struct Layout {
  int off[10] = {}, stride[10] = {};
  constexpr int at(int t, int c) const { return off[t] + c * stride[t]; }
};
constexpr Layout packed_layout(int d) {
  Layout L;
  for (int t = 0; t < position_terms(d); ++t) L.off[t] = d * t, L.stride[t] = 1;
  return L;
}
constexpr Layout kPairs = {{3, 0, 8, 16, 24, 4, 12, 20, 7, 28}, {8, 1, 1, 1, 1, 1, 1, 1, 8, 1}};
constexpr Layout kPacked2 = packed_layout(2), kPacked3 = packed_layout(3);

// The layout of a call: pairs for 3D positions, and for 3D normals on the AVX-512 kernels;
// packed otherwise.
const Layout& layout_for(int d, bool normals, Simd simd) {
  return d == 2 ? kPacked2 : normals && simd != Simd::Avx512 ? kPacked3 : kPairs;
}

// the first 64-byte boundary in a buffer allocated with 16 floats to spare
template <class T>
T* align64(T* p) {
  return reinterpret_cast<T*>((reinterpret_cast<std::uintptr_t>(p) + 63) & ~std::uintptr_t(63));
}

float as_float(std::int32_t w) {
  float f;
  std::memcpy(&f, &w, sizeof f);
  return f;
}

std::int32_t as_word(float f) {
  std::int32_t w;
  std::memcpy(&w, &f, sizeof w);
  return w;
}

// ------------------------------------------------------------------------ portable kernel
// x = (c_0 + b_1 t_1) + (b_2 t_2 + .. + b_d t_d), summed in this order by every kernel (so that
// a positions-only call and a call with normals give the same positions).
template <int D>
void eval_scalar(const std::int32_t* rec, const float* coef, const Layout& L, const float* mrest, float sigma,
                 float* pos, float* nout, long long begin, long long end) {
  constexpr int NC = coef_stride(D);
  constexpr TermIndex ix(D);
  for (long long p = begin; p < end; ++p) {
    const std::int32_t* r = rec + p * (D + 1);
    const long long e = r[0];
    float b[D + 1];
    for (int k = 1; k <= D; ++k) b[k] = as_float(r[k]);
    const float* C = coef + e * NC;
    float t[D + 1][D];  // t_k = c_k + sum_{l >= k} b_l c_kl
    for (int k = 1; k <= D; ++k)
      for (int c = 0; c < D; ++c) {
        t[k][c] = C[L.at(ix.lin[k], c)];
        for (int l = k; l <= D; ++l) t[k][c] += b[l] * C[L.at(ix.quad[k][l], c)];
      }
    float x[D];
    for (int c = 0; c < D; ++c) {
      float rest = b[D] * t[D][c];
      for (int k = D - 1; k >= 2; --k) rest += b[k] * t[k][c];
      x[c] = (C[L.at(0, c)] + b[1] * t[1][c]) + rest;
    }
    for (int c = 0; c < D; ++c) pos[p * D + c] = x[c];
    if (!nout) continue;
    float Dk[D + 1][D];  // Dk[k][c] = component c of dx/db_k
    for (int k = 1; k <= D; ++k)
      for (int c = 0; c < D; ++c) {
        float v = C[L.at(ix.lin[k], c)];
        for (int l = 1; l <= D; ++l) v += (k == l ? 2.0f : 1.0f) * b[l] * C[L.at(ix.quad[k][l], c)];
        Dk[k][c] = sigma * v;
      }
    const float* m = mrest + p * D;
    float o[D];
    if constexpr (D == 3) {
      // cof(D) m: column k of cof(D) is D_{k+1} x D_{k+2}
      for (int c = 0; c < 3; ++c) o[c] = 0;
      for (int k = 1; k <= 3; ++k) {
        const float* u = Dk[k % 3 + 1];
        const float* w = Dk[(k + 1) % 3 + 1];
        o[0] += m[k - 1] * (u[1] * w[2] - u[2] * w[1]);
        o[1] += m[k - 1] * (u[2] * w[0] - u[0] * w[2]);
        o[2] += m[k - 1] * (u[0] * w[1] - u[1] * w[0]);
      }
    } else {
      o[0] = m[0] * Dk[2][1] - m[1] * Dk[1][1];
      o[1] = -m[0] * Dk[2][0] + m[1] * Dk[1][0];
    }
    float sq = 0;
    for (int c = 0; c < D; ++c) sq += o[c] * o[c];
    const float len = std::sqrt(sq);
    // 0 where J is singular: the x86 kernel's threshold, so that both give the same points 0
    for (int c = 0; c < D; ++c) nout[p * D + c] = sq > FLT_MIN ? o[c] / len : 0.0f;
  }
}

#ifdef MBI_FAST_X86
// ------------------------------------------------------------------------ x86 kernels (3D)
// The AVX2 kernels, FMA on 256-bit vectors: positions only (pairs layout, eval_x86_pairs: one point
// and two terms to a vector, 4 aligned 32-byte loads a point) and positions with normals
// (packed layout, eval_x86: two points to a vector (x, y, z, * | x, y, z, *), each term loaded
// 16 bytes at a time). An element's 2 cache lines are prefetched kPrefetch points ahead when the
// points are not stored coherently (random points read the coefficient table from L2, not L1; in
// a mesh's order the prefetches only cost); the input streams (records, rest normals) are
// prefetched kStreamAhead points ahead in either order. Groups of 4 points are written as 3
// aligned 16-byte vectors with streaming stores (the output is not read back by this pass, so it
// bypasses the caches and saves the write-allocate reads).
#define MBI_TARGET __attribute__((target("avx2,fma")))

// Prefetch the byte at p + bytes: integer arithmetic, so that an address past the end of a buffer
// is never formed as a pointer (a prefetch does not fault).
inline void prefetch_at(const void* p, long long bytes) {
  _mm_prefetch(reinterpret_cast<const char*>(reinterpret_cast<std::uintptr_t>(p) + static_cast<std::uintptr_t>(bytes)),
               _MM_HINT_T0);
}

// Prefetch the element terms (both lines) of the 4 points kPrefetch after p (records are padded:
// those are always records).
MBI_TARGET inline void prefetch_terms(const std::int32_t* rec, const float* coef, long long p) {
  for (int k = 0; k < 4; ++k) {
    const char* ahead = reinterpret_cast<const char*>(coef + static_cast<long long>(rec[4 * (p + k + kPrefetch)]) * coef_stride(3));
    _mm_prefetch(ahead, _MM_HINT_T0);
    _mm_prefetch(ahead + 64, _MM_HINT_T0);
  }
}

// term k of elements A (low half) and B (high half)
MBI_TARGET inline __m256 term2(const float* A, const float* B, int k) {
  return _mm256_loadu2_m128(B + 3 * k, A + 3 * k);
}

#define MBI_YZX(v) _mm256_permute_ps((v), _MM_SHUFFLE(3, 0, 2, 1))

// Positions of the 2 points whose records start at r (packed layout) and their derivatives
// D_k = dx/db_k (times sigma when Scaled: of order 1 at any model scale; cof(D) is quadratic in D).
template <bool Scaled>
MBI_TARGET inline void two_points(const std::int32_t* r, const float* coef, __m256 sigma, __m256& x, __m256* D) {
  constexpr int NC = coef_stride(3);
  const __m256 v = _mm256_loadu_ps(reinterpret_cast<const float*>(r));
  const float* A = coef + static_cast<long long>(r[0]) * NC;
  const float* B = coef + static_cast<long long>(r[4]) * NC;
  const __m256 b1 = _mm256_permute_ps(v, 0x55), b2 = _mm256_permute_ps(v, 0xAA), b3 = _mm256_permute_ps(v, 0xFF);
  // terms: 0 c0, 1 c1, 2 c11, 3 c12, 4 c13, 5 c2, 6 c22, 7 c23, 8 c3, 9 c33
  const __m256 c11 = term2(A, B, 2), c12 = term2(A, B, 3), c13 = term2(A, B, 4), c22 = term2(A, B, 6),
               c23 = term2(A, B, 7), c33 = term2(A, B, 9);
  __m256 t1 = _mm256_fmadd_ps(c11, b1, term2(A, B, 1));
  __m256 t2 = _mm256_fmadd_ps(c22, b2, term2(A, B, 5));
  const __m256 t3 = _mm256_fmadd_ps(c33, b3, term2(A, B, 8));
  t1 = _mm256_fmadd_ps(c12, b2, t1);
  t2 = _mm256_fmadd_ps(c23, b3, t2);
  t1 = _mm256_fmadd_ps(c13, b3, t1);
  // (c0 + b1 t1) + (b2 t2 + b3 t3): the pairs kernel's order. Lanes 3 and 7: not coordinates
  // (ignored by the stores).
  x = _mm256_add_ps(_mm256_fmadd_ps(t1, b1, term2(A, B, 0)), _mm256_fmadd_ps(t2, b2, _mm256_mul_ps(t3, b3)));
  D[0] = _mm256_fmadd_ps(c11, b1, t1);
  D[1] = _mm256_fmadd_ps(c22, b2, _mm256_fmadd_ps(c12, b1, t2));
  D[2] = _mm256_fmadd_ps(c33, b3, _mm256_fmadd_ps(c13, b1, _mm256_fmadd_ps(c23, b2, t3)));
  if constexpr (Scaled)
    for (int k = 0; k < 3; ++k) D[k] = _mm256_mul_ps(sigma, D[k]);
}

// cof(D) m of 2 points (lanes 3 and 7 set to 0).
MBI_TARGET inline __m256 cof_times(const __m256* D, __m256 m) {
  const __m256 Y1 = MBI_YZX(D[0]), Y2 = MBI_YZX(D[1]), Y3 = MBI_YZX(D[2]);
  // a x b = (a * b.yzx - a.yzx * b).yzx; the last shuffle is linear, so it is applied once.
  __m256 o = _mm256_mul_ps(_mm256_permute_ps(m, 0x00), _mm256_fmsub_ps(D[1], Y3, _mm256_mul_ps(Y2, D[2])));
  o = _mm256_fmadd_ps(_mm256_permute_ps(m, 0x55), _mm256_fmsub_ps(D[2], Y1, _mm256_mul_ps(Y3, D[0])), o);
  o = _mm256_fmadd_ps(_mm256_permute_ps(m, 0xAA), _mm256_fmsub_ps(D[0], Y2, _mm256_mul_ps(Y1, D[1])), o);
  return _mm256_blend_ps(MBI_YZX(o), _mm256_setzero_ps(), 0x88);
}

// o / |o| for the 2 vectors of o (0 where |o|^2 <= FLT_MIN: J singular).
MBI_TARGET inline __m256 renormalise(__m256 o) {
  const __m256 sq = _mm256_mul_ps(o, o);
  __m256 s = _mm256_add_ps(sq, _mm256_permute_ps(sq, _MM_SHUFFLE(2, 3, 0, 1)));
  s = _mm256_add_ps(s, _mm256_permute_ps(s, _MM_SHUFFLE(1, 0, 3, 2)));
  // 1/sqrt(s): the estimate and one Newton step (relative error about 1e-7)
  __m256 inv = _mm256_rsqrt_ps(s);
  const __m256 half_s = _mm256_mul_ps(_mm256_set1_ps(0.5f), s);
  inv = _mm256_mul_ps(inv, _mm256_fnmadd_ps(_mm256_mul_ps(half_s, inv), inv, _mm256_set1_ps(1.5f)));
  const __m256 ok = _mm256_cmp_ps(s, _mm256_set1_ps(FLT_MIN), _CMP_GT_OQ);
  return _mm256_and_ps(_mm256_mul_ps(o, inv), ok);
}

// 4 results (x, y, z, *) to 3 vectors x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3.
MBI_TARGET inline void pack4(__m128 r0, __m128 r1, __m128 r2, __m128 r3, __m128& o0, __m128& o1, __m128& o2) {
  o0 = _mm_blend_ps(r0, _mm_shuffle_ps(r1, r1, _MM_SHUFFLE(0, 0, 0, 0)), 0x8);
  o1 = _mm_shuffle_ps(r1, r2, _MM_SHUFFLE(1, 0, 2, 1));
  o2 = _mm_blend_ps(_mm_shuffle_ps(r3, r3, _MM_SHUFFLE(2, 1, 0, 0)),
                    _mm_shuffle_ps(r2, r2, _MM_SHUFFLE(2, 2, 2, 2)), 0x1);
}

// the same, two results to a vector
MBI_TARGET inline void pack4(__m256 a, __m256 b, __m128& o0, __m128& o1, __m128& o2) {
  pack4(_mm256_castps256_ps128(a), _mm256_extractf128_ps(a, 1), _mm256_castps256_ps128(b), _mm256_extractf128_ps(b, 1),
        o0, o1, o2);
}

// 12 floats to out: streaming when out is 16-byte aligned.
MBI_TARGET inline void store12(float* out, bool aligned, __m128 o0, __m128 o1, __m128 o2) {
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

// Positions and normals, packed layout, points [begin, end) with end - begin a multiple of 4 (the
// caller runs the rest portably). The work of 4 points runs in three stages over three
// iterations: positions and D (this group), cof(D) m (the group before), renormalisation (the
// one before that). Each stage is a long chain of dependent operations; in one iteration they
// starved the out-of-order window, staggered they overlap (measured: positions + normals 2.4x ->
// 1.7x the time of positions alone).
template <bool Scaled, bool Prefetch>
MBI_TARGET void eval_x86(const std::int32_t* rec, const float* coef, const float* mrest, float sigma,
                         float* pos, float* nout, long long begin, long long end) {
  const __m256 sig = _mm256_set1_ps(sigma);
  const bool aligned = reinterpret_cast<std::uintptr_t>(pos + 3 * begin) % 16 == 0 &&
                       reinterpret_cast<std::uintptr_t>(nout + 3 * begin) % 16 == 0;
  const __m256 zero = _mm256_setzero_ps();
  // D and m of the group at p - 4, cof(D) m of the group at p - 8 (two vectors each)
  __m256 D[2][3] = {{zero, zero, zero}, {zero, zero, zero}}, m[2] = {zero, zero}, o[2] = {zero, zero};
  __m128 o0, o1, o2;
  long long p = begin;
  for (; p < end; p += 4) {
    prefetch_at(rec + 4 * p, 4LL * 4 * kStreamAhead);  // one 64-byte line of records per 4 points
    prefetch_at(mrest + 3 * p, 4LL * 3 * kStreamAhead);
    if constexpr (Prefetch) prefetch_terms(rec, coef, p);
    // stages 3 and 2 (on zeros in the first two iterations: not stored)
    const __m256 n0 = renormalise(o[0]), n1 = renormalise(o[1]);
    o[0] = cof_times(D[0], m[0]);
    o[1] = cof_times(D[1], m[1]);
    __m256 x0, x1;
    two_points<Scaled>(rec + 4 * p, coef, sig, x0, D[0]);
    two_points<Scaled>(rec + 4 * (p + 2), coef, sig, x1, D[1]);
    pack4(x0, x1, o0, o1, o2);
    store12(pos + 3 * p, aligned, o0, o1, o2);
    m[0] = _mm256_loadu2_m128(mrest + 3 * (p + 1), mrest + 3 * p);
    m[1] = _mm256_loadu2_m128(mrest + 3 * (p + 3), mrest + 3 * (p + 2));
    if (p - begin >= 8) {
      pack4(n0, n1, o0, o1, o2);
      store12(nout + 3 * (p - 8), aligned, o0, o1, o2);
    }
  }
  // the last two groups: o holds the one at p - 8, D and m the one at p - 4
  if (p - begin >= 8) {
    pack4(renormalise(o[0]), renormalise(o[1]), o0, o1, o2);
    store12(nout + 3 * (p - 8), aligned, o0, o1, o2);
  }
  if (p - begin >= 4) {
    pack4(renormalise(cof_times(D[0], m[0])), renormalise(cof_times(D[1], m[1])), o0, o1, o2);
    store12(nout + 3 * (p - 4), aligned, o0, o1, o2);
  }
  _mm_sfence();
}

// Positions only, pairs layout: one point to a 256-bit vector, two terms to it, the element's
// 128 bytes read with 4 aligned 32-byte loads (the packed layout needs 20 16-byte loads for 2
// points, most of them straddling 16-byte boundaries: 1.1-1.15x the time of this kernel).
//   T = (c1 | c2) + (b1 | b2)(c11 | c22) + (b2 | b3)(c12 | c23) + (b3 | 0)(c13 | c33) = (t1 | t2)
//   U = (c0 | c3) + (0 | b3)(c13 | c33) = (c0 | t3)
//   x = lo + hi of (b1 | b2) T + (1 | b3) U = (c0 + b1 t1) + (b2 t2 + b3 t3)
MBI_TARGET inline __m128 one_point(const float* C, const std::int32_t* r, __m256i sel12, __m256i sel23) {
  const __m256 rb = _mm256_broadcast_ps(reinterpret_cast<const __m128*>(r));  // (e, b1, b2, b3) twice
  const __m256 L0 = _mm256_load_ps(C), L1 = _mm256_load_ps(C + 8), L2 = _mm256_load_ps(C + 16),
               L3 = _mm256_load_ps(C + 24);
  const __m256 b12 = _mm256_permutevar_ps(rb, sel12), b23 = _mm256_permutevar_ps(rb, sel23);
  const __m256 b33 = _mm256_permute_ps(rb, 0xFF), zero = _mm256_setzero_ps();
  // (c0 | c3) from the slots' 4th floats: (c1z, c11z, c0x, c0y | c2z, c22z, c3x, c3y), then z
  const __m256 c03 = _mm256_shuffle_ps(_mm256_unpackhi_ps(L0, L1), L2, _MM_SHUFFLE(3, 3, 3, 2));
  __m256 T = _mm256_fmadd_ps(L1, b12, L0);
  T = _mm256_fmadd_ps(L2, b23, T);
  T = _mm256_fmadd_ps(L3, _mm256_blend_ps(b33, zero, 0xF0), T);
  const __m256 U = _mm256_fmadd_ps(L3, _mm256_blend_ps(zero, b33, 0xF0), c03);
  const __m256 V = _mm256_fmadd_ps(b12, T, _mm256_mul_ps(U, _mm256_blend_ps(_mm256_set1_ps(1.0f), b33, 0xF0)));
  return _mm_add_ps(_mm256_castps256_ps128(V), _mm256_extractf128_ps(V, 1));  // lane 3: not a coordinate
}

template <bool Prefetch>
MBI_TARGET void eval_x86_pairs(const std::int32_t* rec, const float* coef, const float*, float, float* pos, float*,
                               long long begin, long long end) {
  constexpr int NC = coef_stride(3);
  const __m256i sel12 = _mm256_setr_epi32(1, 1, 1, 1, 2, 2, 2, 2), sel23 = _mm256_setr_epi32(2, 2, 2, 2, 3, 3, 3, 3);
  const bool aligned = reinterpret_cast<std::uintptr_t>(pos + 3 * begin) % 16 == 0;
  for (long long p = begin; p < end; p += 4) {
    prefetch_at(rec + 4 * p, 4LL * 4 * kStreamAhead);
    if constexpr (Prefetch) prefetch_terms(rec, coef, p);
    __m128 x[4];
    for (int k = 0; k < 4; ++k) {
      const std::int32_t* r = rec + 4 * (p + k);
      x[k] = one_point(coef + static_cast<long long>(r[0]) * NC, r, sel12, sel23);
    }
    __m128 o0, o1, o2;
    pack4(x[0], x[1], x[2], x[3], o0, o1, o2);
    store12(pos + 3 * p, aligned, o0, o1, o2);
  }
  _mm_sfence();
}

#define MBI_TARGET512 __attribute__((target("avx512f,avx512dq,avx512vl,avx2,fma")))
// GCC 12's AVX-512 intrinsics fill unused lanes from _mm512_undefined_*() and then warn that
// they may be (or are) used uninitialized (GCC bug 105593); no lane of those is ever read here.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"

// 8 floats at A + k (low half) and at B + k (high half), 32-byte aligned
MBI_TARGET512 inline __m512 halves(const float* A, const float* B, int k) {
  return _mm512_insertf32x8(_mm512_castps256_ps512(_mm256_load_ps(A + k)), _mm256_load_ps(B + k), 1);
}

#define MBI_SWAP512(v) _mm512_shuffle_f32x4((v), (v), _MM_SHUFFLE(2, 3, 0, 1))  // the 128-bit halves of each 256
#define MBI_YZX512(v) _mm512_permute_ps((v), _MM_SHUFFLE(3, 0, 2, 1))

// Index vectors of the 512-bit kernels (loaded once per call).
struct Idx512 {
  __m512i rot, out;
  MBI_TARGET512 Idx512()
      : rot(_mm512_setr_epi32(0, 1, 2, 3, 1, 2, 3, 0, 4, 5, 6, 7, 5, 6, 7, 4)),
        out(_mm512_setr_epi32(0, 1, 2, 8, 9, 10, 16, 17, 18, 24, 25, 26, 0, 0, 0, 0)) {}
};

// Two points whose records start at r (A in the low 256 bits, B in the high), pairs layout: each
// half computes what one_point computes, in the same order (masks for its blends). Returns
// (x_A, ., x_B, .) in 128-bit lanes 0 and 2. With Derivs also X = (D_1 | D_2) and Ad = (. | D_3)
// in each point's 256 bits (D_k = dx/db_k; summed in another order than the packed kernel's).
template <bool Derivs>
MBI_TARGET512 inline __m512 pair512(const std::int32_t* r, const float* coef, const Idx512& I, __m512& X, __m512& Ad) {
  constexpr int NC = coef_stride(3);
  const float* A = coef + static_cast<long long>(r[0]) * NC;
  const float* B = coef + static_cast<long long>(r[4]) * NC;
  const __m512 v = _mm512_castps256_ps512(_mm256_loadu_ps(reinterpret_cast<const float*>(r)));
  const __m512 L0 = halves(A, B, 0), L1 = halves(A, B, 8), L2 = halves(A, B, 16), L3 = halves(A, B, 24);
  // (rA, rA' | rB, rB'), r' = (b1, b2, b3, e): one cross-lane permute, then every coefficient
  // vector by an in-lane one with the same pattern in each 128-bit lane (twice the throughput)
  const __m512 v2 = _mm512_permutexvar_ps(I.rot, v);
  const __m512 b12 = _mm512_permute_ps(v2, 0x55), b23 = _mm512_permute_ps(v2, 0xAA);
  const __m512 b3lo = _mm512_maskz_permute_ps(0x0F0F, v2, 0xFF), b3hi = _mm512_maskz_permute_ps(0xF0F0, v2, 0xAA);
  const __m512 ob3 = _mm512_mask_permute_ps(_mm512_set1_ps(1.0f), 0xF0F0, v2, 0xAA);
  // (c0 | c3) from the slots' 4th floats, as one_point
  const __m512 c03 = _mm512_shuffle_ps(_mm512_unpackhi_ps(L0, L1), L2, _MM_SHUFFLE(3, 3, 3, 2));
  __m512 T = _mm512_fmadd_ps(L1, b12, L0);
  T = _mm512_fmadd_ps(L2, b23, T);
  T = _mm512_fmadd_ps(L3, b3lo, T);                                       // (t1 | t2)
  const __m512 U = _mm512_fmadd_ps(L3, b3hi, c03);                        // (c0 | t3)
  const __m512 V = _mm512_fmadd_ps(b12, T, _mm512_mul_ps(U, ob3));
  if constexpr (Derivs) {
    // (0 | b1); then every lane computed holds a sum of finite terms (v2's e is an integer)
    const __m512 b1hi = _mm512_maskz_permute_ps(0xF0F0, v2, 0x00);
    // (t1 + b1 c11 | t2 + b2 c22), then b1 c12 added to the high half: (D1 | D2). Neither
    // chain waits on the other (D_2 | D_3 from X through a swap and blends took 1.06x the time
    // of the whole pass with normals).
    X = _mm512_mask3_fmadd_ps(MBI_SWAP512(L2), b1hi, _mm512_fmadd_ps(L1, b12, T), 0xF0F0);
    // (. | t3 + b3 c33 + b2 c23 + b1 c13) = (. | D3)
    Ad = _mm512_fmadd_ps(MBI_SWAP512(L3), b1hi, _mm512_fmadd_ps(L2, b12, _mm512_fmadd_ps(L3, b3hi, U)));
  }
  return _mm512_add_ps(V, MBI_SWAP512(V));  // (c0 + b1 t1) + (b2 t2 + b3 t3)
}

// The 12 floats of 4 points from two pair512 results to 3 stores.
MBI_TARGET512 inline void store4(float* out, bool aligned, const Idx512& I, __m512 W0, __m512 W1) {
  const __m512 o = _mm512_permutex2var_ps(W0, I.out, W1);
  store12(out, aligned, _mm512_castps512_ps128(o), _mm512_extractf32x4_ps(o, 1), _mm512_extractf32x4_ps(o, 2));
}

// Positions only, pairs layout, two points to a 512-bit vector, 4 points an iteration.
template <bool Prefetch>
MBI_TARGET512 void eval_x86_pairs512(const std::int32_t* rec, const float* coef, const float*, float, float* pos,
                                     float*, long long begin, long long end) {
  const Idx512 I;
  const bool aligned = reinterpret_cast<std::uintptr_t>(pos + 3 * begin) % 16 == 0;
  __m512 none;
  for (long long p = begin; p < end; p += 4) {
    prefetch_at(rec + 4 * p, 4LL * 4 * kStreamAhead);
    if constexpr (Prefetch) prefetch_terms(rec, coef, p);
    const __m512 W0 = pair512<false>(rec + 4 * p, coef, I, none, none);
    const __m512 W1 = pair512<false>(rec + 4 * (p + 2), coef, I, none, none);
    store4(pos + 3 * p, aligned, I, W0, W1);
  }
  _mm_sfence();
}

// o / |o| for the 4 vectors of o (lane 3 of each 0; 0 where |o|^2 <= FLT_MIN: J singular).
MBI_TARGET512 inline __m512 renormalise512(__m512 o) {
  const __m512 sq = _mm512_mul_ps(o, o);
  __m512 s = _mm512_add_ps(sq, _mm512_permute_ps(sq, _MM_SHUFFLE(2, 3, 0, 1)));
  s = _mm512_add_ps(s, _mm512_permute_ps(s, _MM_SHUFFLE(1, 0, 3, 2)));
  __m512 inv = _mm512_rsqrt14_ps(s);
  inv = _mm512_mul_ps(inv, _mm512_fnmadd_ps(_mm512_mul_ps(_mm512_mul_ps(_mm512_set1_ps(0.5f), s), inv), inv,
                                            _mm512_set1_ps(1.5f)));
  return _mm512_maskz_mul_ps(_mm512_cmp_ps_mask(s, _mm512_set1_ps(FLT_MIN), _CMP_GT_OQ), o, inv);
}

// The normals of 4 points (X[h], Ad[h] from pair512, h = 0, 1; m the first 12 floats of M), one
// point to a 128-bit lane (x, y, z, 0): cof(D) m = D_2 x (m_1 D_3 - m_3 D_1) + m_2 (D_3 x D_1), two
// cross products at once ((D_2 | D_3) x (m_1 D_3 - m_3 D_1 | m_2 D_1)), then the halves added.
template <bool Scaled>
MBI_TARGET512 inline __m512 normals4(const __m512* X, const __m512* Ad, __m512 M, __m512 sig) {
  const __m512i imerge = _mm512_setr_epi32(0, 1, 2, 3, 8, 9, 10, 11, 16, 17, 18, 19, 24, 25, 26, 27);
  const __m512i im12[2] = {_mm512_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1, 3, 3, 3, 3, 4, 4, 4, 4),
                           _mm512_setr_epi32(6, 6, 6, 6, 7, 7, 7, 7, 9, 9, 9, 9, 10, 10, 10, 10)};
  const __m512i im3[2] = {_mm512_setr_epi32(2, 2, 2, 2, 2, 2, 2, 2, 5, 5, 5, 5, 5, 5, 5, 5),
                          _mm512_setr_epi32(8, 8, 8, 8, 8, 8, 8, 8, 11, 11, 11, 11, 11, 11, 11, 11)};
  __m512 O[2];
  for (int h = 0; h < 2; ++h) {
    __m512 D1 = X[h], D23 = _mm512_mask_blend_ps(0xF0F0, MBI_SWAP512(X[h]), Ad[h]);  // (D1 | D2), (D2 | D3)
    if constexpr (Scaled) D1 = _mm512_mul_ps(sig, D1), D23 = _mm512_mul_ps(sig, D23);
    const __m512 m12 = _mm512_permutexvar_ps(im12[h], M), m30 = _mm512_maskz_permutexvar_ps(0x0F0F, im3[h], M);
    const __m512 D31 = MBI_SWAP512(_mm512_mask_blend_ps(0xF0F0, D1, D23));                 // (D3 | D1)
    const __m512 Bv = _mm512_fnmadd_ps(D1, m30, _mm512_mul_ps(D31, m12));                 // (m1 D3 - m3 D1 | m2 D1)
    const __m512 C = _mm512_fmsub_ps(D23, MBI_YZX512(Bv), _mm512_mul_ps(MBI_YZX512(D23), Bv));  // (a x b).zxy
    O[h] = _mm512_add_ps(C, MBI_SWAP512(C));
  }
  return renormalise512(MBI_YZX512(_mm512_maskz_permutex2var_ps(0x7777, O[0], imerge, O[1])));
}

// 3-vectors of 16 points, one component to a register.
struct Soa3 {
  __m512 x, y, z;
};

// The 4 registers' 128-bit lanes hold vectors (x, y, z, .): lane 4 g + k of the result holds
// P[k]'s lane g (a 4 x 4 transposition within each 128-bit lane).
MBI_TARGET512 inline Soa3 to_soa(__m512 P0, __m512 P1, __m512 P2, __m512 P3) {
  const __m512 t0 = _mm512_unpacklo_ps(P0, P1), t1 = _mm512_unpackhi_ps(P0, P1);
  const __m512 t2 = _mm512_unpacklo_ps(P2, P3), t3 = _mm512_unpackhi_ps(P2, P3);
  return {_mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0)), _mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2)),
          _mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0))};
}

// Constants of Normals16: which 128-bit lanes to merge.
struct Idx16 {
  __m512i lo, hi;
  MBI_TARGET512 Idx16()
      : lo(_mm512_setr_epi32(0, 1, 2, 3, 8, 9, 10, 11, 16, 17, 18, 19, 24, 25, 26, 27)),
        hi(_mm512_setr_epi32(4, 5, 6, 7, 12, 13, 14, 15, 20, 21, 22, 23, 28, 29, 30, 31)) {}
};

// The normals of 16 points in four phases, so that the kernel can interleave them with the
// positions of the next 16 (each phase alone is a chain of dependent steps): the derivatives
// of pair512 moved to one component a register (16 points a register, lane 4 g + k holding
// point 4 k + g; m is stored in that order by set_rest_normals), cof(D) m = D_2 x (m_1 D_3 -
// m_3 D_1) + m_2 (D_3 x D_1) with whole registers, the renormalisation, and back to
// interleaved xyz.
struct Normals16 {
  Soa3 D1, D2, D3;
  __m512 m1, m2, m3, wx, wy, wz;

  // 0: the derivatives of 4 points (two pair512 results) as D_1, D_2, D_3 each one point to a
  // 128-bit lane, right after their positions (12 registers for 16 points instead of 16)
  MBI_TARGET512 static void gather4(const __m512* X, const __m512* Ad, const Idx16& I, __m512* G) {
    G[0] = _mm512_permutex2var_ps(X[0], I.lo, X[1]);
    G[1] = _mm512_permutex2var_ps(X[0], I.hi, X[1]);
    G[2] = _mm512_permutex2var_ps(Ad[0], I.hi, Ad[1]);
  }
  // 1: D_1, D_2 and D_3 of the 16 points (G[3 j + k]: D_(k+1) of points 4 j .. 4 j + 3)
  MBI_TARGET512 void phase1(const __m512* G) {
    D1 = to_soa(G[0], G[3], G[6], G[9]);
    D2 = to_soa(G[1], G[4], G[7], G[10]);
    D3 = to_soa(G[2], G[5], G[8], G[11]);
  }
  // 2: the scale, m (48 floats at mr)
  template <bool Scaled>
  MBI_TARGET512 void phase2(const float* mr, __m512 sig) {
    if constexpr (Scaled)
      for (Soa3* D : {&D1, &D2, &D3})
        D->x = _mm512_mul_ps(sig, D->x), D->y = _mm512_mul_ps(sig, D->y), D->z = _mm512_mul_ps(sig, D->z);
    m1 = _mm512_loadu_ps(mr), m2 = _mm512_loadu_ps(mr + 16), m3 = _mm512_loadu_ps(mr + 32);
  }
  // 3: E = m1 D3 - m3 D1, w = D2 x E + m2 (D3 x D1), renormalised (0 where |w|^2 <= FLT_MIN)
  MBI_TARGET512 void phase3() {
    const __m512 Ex = _mm512_fnmadd_ps(m3, D1.x, _mm512_mul_ps(m1, D3.x));
    const __m512 Ey = _mm512_fnmadd_ps(m3, D1.y, _mm512_mul_ps(m1, D3.y));
    const __m512 Ez = _mm512_fnmadd_ps(m3, D1.z, _mm512_mul_ps(m1, D3.z));
    wx = _mm512_fmadd_ps(m2, _mm512_fmsub_ps(D3.y, D1.z, _mm512_mul_ps(D3.z, D1.y)),
                         _mm512_fmsub_ps(D2.y, Ez, _mm512_mul_ps(D2.z, Ey)));
    wy = _mm512_fmadd_ps(m2, _mm512_fmsub_ps(D3.z, D1.x, _mm512_mul_ps(D3.x, D1.z)),
                         _mm512_fmsub_ps(D2.z, Ex, _mm512_mul_ps(D2.x, Ez)));
    wz = _mm512_fmadd_ps(m2, _mm512_fmsub_ps(D3.x, D1.y, _mm512_mul_ps(D3.y, D1.x)),
                         _mm512_fmsub_ps(D2.x, Ey, _mm512_mul_ps(D2.y, Ex)));
    const __m512 s = _mm512_fmadd_ps(wz, wz, _mm512_fmadd_ps(wy, wy, _mm512_mul_ps(wx, wx)));
    __m512 inv = _mm512_rsqrt14_ps(s);
    inv = _mm512_mul_ps(inv, _mm512_fnmadd_ps(_mm512_mul_ps(_mm512_mul_ps(_mm512_set1_ps(0.5f), s), inv), inv,
                                              _mm512_set1_ps(1.5f)));
    const __mmask16 ok = _mm512_cmp_ps_mask(s, _mm512_set1_ps(FLT_MIN), _CMP_GT_OQ);
    wx = _mm512_maskz_mul_ps(ok, wx, inv), wy = _mm512_maskz_mul_ps(ok, wy, inv), wz = _mm512_maskz_mul_ps(ok, wz, inv);
  }
  // 4: to out (48 floats), point 4 k + g's vector from lane 4 g + k
  MBI_TARGET512 void phase4(float* out, bool aligned) const {
    const __m512 zero = _mm512_setzero_ps();
    const __m512 u0 = _mm512_unpacklo_ps(wx, wy), u1 = _mm512_unpackhi_ps(wx, wy);
    const __m512 v0 = _mm512_unpacklo_ps(wz, zero), v1 = _mm512_unpackhi_ps(wz, zero);
    const __m512 Q[4] = {_mm512_shuffle_ps(u0, v0, _MM_SHUFFLE(1, 0, 1, 0)), _mm512_shuffle_ps(u0, v0, _MM_SHUFFLE(3, 2, 3, 2)),
                         _mm512_shuffle_ps(u1, v1, _MM_SHUFFLE(1, 0, 1, 0)), _mm512_shuffle_ps(u1, v1, _MM_SHUFFLE(3, 2, 3, 2))};
    const __m512i pack = _mm512_setr_epi32(0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, 0, 0, 0, 0);
    for (int k = 0; k < 4; ++k) {  // Q[k]: points 4 k .. 4 k + 3 as (x, y, z, 0)
      const __m512 n = _mm512_permutexvar_ps(pack, Q[k]);
      store12(out + 12 * k, aligned, _mm512_castps512_ps128(n), _mm512_extractf32x4_ps(n, 1), _mm512_extractf32x4_ps(n, 2));
    }
  }
};

template <bool Scaled, bool Prefetch>
// Positions and normals, pairs layout, two points to a 512-bit vector, 16 points an iteration:
// the positions 4 at a time (exactly as eval_x86_pairs512), and after each group of 4 one phase
// of the normals of the 16 points before (Normals16), then the last groups of 4 (normals4). No
// scratch block: each group's derivatives go, one point to a 128-bit lane, into 12 registers
// (gather4), which phase 1 of the next group reads whole before they are overwritten (no copy
// between groups; the compiler spills some to the stack). A block of derivatives for 128 points
// cost more in L1 misses (its lines evicted by the element terms of random points) and 4K
// aliasing than the normals themselves.
MBI_TARGET512 void eval_x86_normals512(const std::int32_t* rec, const float* coef, const float* mrest, float sigma,
                                       float* pos, float* nout, long long begin, long long end) {
  const Idx512 I;
  const Idx16 I16;
  const __m512 sig = _mm512_set1_ps(sigma);
  const bool aligned = reinterpret_cast<std::uintptr_t>(pos + 3 * begin) % 16 == 0 &&
                       reinterpret_cast<std::uintptr_t>(nout + 3 * begin) % 16 == 0;
  const long long end16 = begin + (end - begin) / 16 * 16;
  __m512 X[2], Ad[2], G[12];
  Normals16 N;
  long long p = begin;
  for (; p < end16; p += 16) {
    const bool prev = p > begin;
    for (int q = 0; q < 4; ++q) {
      const long long g = p + 4 * q;
      prefetch_at(rec + 4 * g, 4LL * 4 * kStreamAhead);
      prefetch_at(mrest + 3 * g, 4LL * 3 * kStreamAhead);
      if constexpr (Prefetch) prefetch_terms(rec, coef, g);
      const __m512 W0 = pair512<true>(rec + 4 * g, coef, I, X[0], Ad[0]);
      const __m512 W1 = pair512<true>(rec + 4 * (g + 2), coef, I, X[1], Ad[1]);
      store4(pos + 3 * g, aligned, I, W0, W1);
      if (prev) {  // phase 1 reads all of the previous group's G before gather4 overwrites it
        if (q == 0) N.phase1(G);
        if (q == 1) N.phase2<Scaled>(mrest + 3 * (p - 16), sig);
        if (q == 2) N.phase3();
        if (q == 3) N.phase4(nout + 3 * (p - 16), aligned);
      }
      Normals16::gather4(X, Ad, I16, G + 3 * q);
    }
  }
  if (p > begin) {
    N.phase1(G);
    N.phase2<Scaled>(mrest + 3 * (p - 16), sig);
    N.phase3();
    N.phase4(nout + 3 * (p - 16), aligned);
  }
  const __m512i pack = _mm512_setr_epi32(0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, 0, 0, 0, 0);
  for (; p < end; p += 4) {
    const __m512 W0 = pair512<true>(rec + 4 * p, coef, I, X[0], Ad[0]);
    const __m512 W1 = pair512<true>(rec + 4 * (p + 2), coef, I, X[1], Ad[1]);
    store4(pos + 3 * p, aligned, I, W0, W1);
    const __m512 n = _mm512_permutexvar_ps(pack, normals4<Scaled>(X, Ad, _mm512_loadu_ps(mrest + 3 * p), sig));
    store12(nout + 3 * p, aligned, _mm512_castps512_ps128(n), _mm512_extractf32x4_ps(n, 1), _mm512_extractf32x4_ps(n, 2));
  }
  _mm_sfence();
}
#pragma GCC diagnostic pop

using KernelX86 = void (*)(const std::int32_t*, const float*, const float*, float, float*, float*, long long,
                           long long);

// The x86 kernel for: the instruction set (Avx512 or Avx2), normals or not, D scaled or not
// (only with normals), prefetches or not.
KernelX86 pick_x86(Simd simd, bool normals, bool scaled, bool prefetch) {
  static constexpr KernelX86 avx2[3][2] = {
      {eval_x86_pairs<false>, eval_x86_pairs<true>},
      {eval_x86<false, false>, eval_x86<false, true>},
      {eval_x86<true, false>, eval_x86<true, true>},
  };
  static constexpr KernelX86 avx512[3][2] = {
      {eval_x86_pairs512<false>, eval_x86_pairs512<true>},
      {eval_x86_normals512<false, false>, eval_x86_normals512<false, true>},
      {eval_x86_normals512<true, false>, eval_x86_normals512<true, true>},
  };
  return (simd == Simd::Avx512 ? avx512 : avx2)[normals ? (scaled ? 2 : 1) : 0][prefetch ? 1 : 0];
}

#endif

// ------------------------------------------------------------------------ coefficients
// The terms of elements [0, m) from their Bezier points B ((m K) x D, K = (D+1)(D+2)/2, the
// vertices then the edges in the order of bezier_edges(D)), computed in double and rounded to
// float once, written in layout L; the floats no term uses are set to 0 (a call may change the
// layout; the kernels read them but ignore what they give). Returns the largest |c_k| (the
// scale of the derivatives dx/db_k). Everything below is known at compile time but B: no scratch
// to clear, no offset table to read per element (1,764 elements on one thread, medians of 3,000
// calls against the layout tables read at run time: 79 -> 34-56 us).
template <int D, const Layout& L>
double prepare_terms(const BezierPoints& B, float* coef, int m, int threads) {
  constexpr int K = (D + 1) * (D + 2) / 2, NC = coef_stride(D);
  static constexpr TermIndex ix(D);
  constexpr auto unused = [] {
    std::array<bool, NC> free{};
    for (bool& f : free) f = true;
    for (int c = 0; c < D; ++c) {
      free[L.at(0, c)] = false;
      for (int k = 1; k <= D; ++k) {
        free[L.at(ix.lin[k], c)] = false;
        for (int l = k; l <= D; ++l) free[L.at(ix.quad[k][l], c)] = false;
      }
    }
    return free;
  }();
  // row of the Bezier point on edge (i, j) within an element's K rows
  int edge_row[D + 1][D + 1] = {};
  const auto& edges = bezier_edges(D);
  for (size_t s = 0; s < edges.size(); ++s)
    edge_row[edges[s].first][edges[s].second] = edge_row[edges[s].second][edges[s].first] =
        D + 1 + static_cast<int>(s);
  const double* col[D];
  for (int c = 0; c < D; ++c) col[c] = B.data() + c * B.rows();  // B is column-major
  double dmax = 0;
  MBI_OMP("omp parallel for schedule(static) num_threads(threads) if (m > 512) reduction(max : dmax)")
  for (int e = 0; e < m; ++e) {
    const long long row = static_cast<long long>(e) * K;
    float* C = coef + static_cast<size_t>(e) * NC;
    for (int f = 0; f < NC; ++f)
      if (unused[f]) C[f] = 0.0f;
    for (int c = 0; c < D; ++c) {
      const double* P = col[c] + row;
      auto Pe = [&](int i, int j) { return P[edge_row[i][j]]; };
      C[L.at(0, c)] = static_cast<float>(P[0]);
      for (int k = 1; k <= D; ++k) {
        const double ck = 2 * (Pe(0, k) - P[0]);
        dmax = std::max(dmax, std::abs(ck));
        C[L.at(ix.lin[k], c)] = static_cast<float>(ck);
        C[L.at(ix.quad[k][k], c)] = static_cast<float>(P[0] + P[k] - 2 * Pe(0, k));
        for (int l = k + 1; l <= D; ++l)
          C[L.at(ix.quad[k][l], c)] = static_cast<float>(2 * (P[0] - Pe(0, k) - Pe(0, l) + Pe(k, l)));
      }
    }
  }
  return dmax;
}

}  // namespace

bool FastEvaluator::supported(Simd s) {
#ifdef MBI_FAST_X86
  if (s == Simd::Avx512) return detail::have_avx512();
  if (s == Simd::Avx2) return detail::have_avx2_fma();
#else
  if (s == Simd::Avx512 || s == Simd::Avx2) return false;
#endif
  return true;
}

const char* FastEvaluator::name(Simd s) {
  switch (s) {
    case Simd::Auto: return "auto";
    case Simd::Avx512: return "avx512";
    case Simd::Avx2: return "avx2";
    case Simd::Portable: return "portable";
  }
  return "?";
}

FastEvaluator::FastEvaluator(const Embedding& emb, int threads, Simd simd) : threads_(threads) {
  d_ = emb.dim();
  if (d_ != 2 && d_ != 3)
    throw Error("FastEvaluator: the embedding must be 2D or 3D (bary with 3 or 4 columns), got " +
                std::to_string(emb.bary.cols()) + " columns");
  if (simd != Simd::Auto && !supported(simd))
    throw Error(std::string("FastEvaluator: this CPU cannot run the ") + name(simd) + " kernels");
  if (simd == Simd::Auto) simd = supported(Simd::Avx512) ? Simd::Avx512 : supported(Simd::Avx2) ? Simd::Avx2 : Simd::Portable;
  simd_ = d_ == 3 ? simd : Simd::Portable;
  if (emb.bary.rows() != emb.element.size())
    throw Error("FastEvaluator: embedding has " + std::to_string(emb.element.size()) + " elements but " +
                std::to_string(emb.bary.rows()) + " coordinate rows");
  if (threads < 0) throw Error("FastEvaluator: threads must be >= 0 (0 = all cores)");
  p_ = emb.size();
  const int d = d_;
  m_ = 0;
  for (long long i = 0; i < p_; ++i) {
    if (emb.element(i) < 0)
      throw Error("FastEvaluator: point " + std::to_string(i) + " refers to element " +
                  std::to_string(emb.element(i)));
    m_ = std::max(m_, emb.element(i) + 1);
  }
  if (emb.gradients.rows() > 0) {
    if (emb.gradients.cols() != d || emb.gradients.rows() % (d + 1) != 0 ||
        emb.gradients.rows() / (d + 1) < m_)
      throw Error("FastEvaluator: the embedding's basis gradients are " +
                  std::to_string(emb.gradients.rows()) + " x " + std::to_string(emb.gradients.cols()) +
                  ", expected (m (d+1)) x d with m >= " + std::to_string(m_));
    m_ = static_cast<int>(emb.gradients.rows() / (d + 1));
    grads_.resize(static_cast<size_t>(m_) * d * d);
    for (int e = 0; e < m_; ++e)
      for (int k = 1; k <= d; ++k)
        for (int r = 0; r < d; ++r)
          grads_[(static_cast<size_t>(e) * d + (k - 1)) * d + r] =
              emb.gradients(static_cast<Eigen::Index>(e) * (d + 1) + k, r);
  }
  // records: one block (the x86 kernel loads two 3D records as one 32-byte vector), then
  // kPrefetch records of element 0 for the prefetches past the end
  records_.assign(static_cast<size_t>(p_ + kPrefetch) * (d + 1), 0);
  // Points stored coherently (a mesh's vertices: most follow a point of the same element) find
  // their element's terms in L1 already; the prefetches only help points in random order.
  long long same = 0;
  for (long long i = 1; i < p_; ++i) same += emb.element(i) == emb.element(i - 1);
  coherent_ = 2 * same >= p_;
  for (long long i = 0; i < p_; ++i) {
    std::int32_t* r = records_.data() + i * (d + 1);
    r[0] = emb.element(i);
    for (int k = 1; k <= d; ++k) r[k] = as_word(static_cast<float>(emb.bary(i, k)));
  }
}

void FastEvaluator::set_rest_normals(const Eigen::Ref<const Eigen::MatrixXd>& normals) {
  if (normals.rows() != p_ || normals.cols() != d_)
    throw Error("FastEvaluator: rest normals must be " + std::to_string(p_) + " x " + std::to_string(d_) +
                ", got " + std::to_string(normals.rows()) + " x " + std::to_string(normals.cols()));
  if (grads_.empty() && p_ > 0)
    throw Error("FastEvaluator: normals need the embedding's basis gradients (filled by embed())");
  // m = cof(A)^T n per point, A = [a_1 .. a_d] (the element's basis gradients as columns):
  // m_k = n . (column k of cof(A)); in 3D column k is a_{k+1} x a_{k+2}.
  // padding: 16-byte loads of the last one, and room to move the block (rest_normals_for())
  normals_.assign(static_cast<size_t>(p_) * d_ + 4 + kSlack, 0.0f);
  moff_ = 0;
  moves_ = 0;
  const int d = d_;
  for (long long i = 0; i < p_; ++i) {
    const double* a = grads_.data() + static_cast<size_t>(records_[static_cast<size_t>(i) * (d + 1)]) * d * d;
    auto g = [&](int k, int r) { return a[(k - 1) * d + r]; };  // component r of a_k
    double n[3] = {normals(i, 0), normals(i, 1), d == 3 ? normals(i, 2) : 0.0}, m[3] = {};
    if (d == 3) {
      for (int k = 1; k <= 3; ++k) {
        const int u = k % 3 + 1, w = (k + 1) % 3 + 1;
        m[k - 1] = n[0] * (g(u, 1) * g(w, 2) - g(u, 2) * g(w, 1)) + n[1] * (g(u, 2) * g(w, 0) - g(u, 0) * g(w, 2)) +
                   n[2] * (g(u, 0) * g(w, 1) - g(u, 1) * g(w, 0));
      }
    } else {
      m[0] = n[0] * g(2, 1) - n[1] * g(2, 0);
      m[1] = -n[0] * g(1, 1) + n[1] * g(1, 0);
    }
    // Only m's direction matters (the normal is renormalised) and |m| ~ 1/h^2 for elements of
    // size h: a power of 2 brings its largest component to [0.5, 1) (exact, any scale).
    double big = 0;
    for (int c = 0; c < d; ++c) big = std::max(big, std::abs(m[c]));
    int ex = 0;
    if (std::isfinite(big) && big > 0) std::frexp(big, &ex);
    for (int c = 0; c < d; ++c)
      normals_[static_cast<size_t>(i) * d + c] = static_cast<float>(std::ldexp(m[c], -ex));
  }
  // The AVX-512 kernel takes each whole group of 16 points (groups start at multiples of 16:
  // every thread's block does) as three registers, one component each, lane 4 g + k holding
  // point 4 k + g (Normals16): stored in that order, it loads them without a permute. The last,
  // partial group stays point by point (the 4-point and portable tails read it so).
  if (simd_ == Simd::Avx512 && d == 3) {
    float g[48];
    for (long long q = 0; q + 16 <= p_; q += 16) {
      float* block = normals_.data() + 3 * q;
      for (int c = 0; c < 3; ++c)
        for (int l = 0; l < 16; ++l) g[16 * c + l] = block[3 * (4 * (l % 4) + l / 4) + c];
      std::copy(g, g + 48, block);
    }
  }
}

int FastEvaluator::threads() const {
#ifdef _OPENMP
  int t = threads_ > 0 ? threads_ : omp_get_max_threads();
#else
  const int t = 1;
#endif
  // at least kBlock points a thread: below that the fork/join costs more than it saves
  const long long cap = std::max<long long>(1, p_ / kBlock);
  return static_cast<int>(std::max<long long>(1, std::min<long long>(t, cap)));
}

void FastEvaluator::prepare(const BezierPoints& B, bool normals) {
  const int d = d_;
  const int K = (d + 1) * (d + 2) / 2;
  if (B.cols() != d || B.rows() % K != 0 || B.rows() / K < m_)
    throw Error("FastEvaluator: Bezier points must be (m " + std::to_string(K) + ") x " +
                std::to_string(d) + " with m >= " + std::to_string(m_) + ", got " +
                std::to_string(B.rows()) + " x " + std::to_string(B.cols()));
  if (normals && !has_rest_normals()) throw Error("FastEvaluator: normals asked for, but no rest normals were set");
  coef_.resize(static_cast<size_t>(m_) * coef_stride(d) + 16);
  float* const coef = align64(coef_.data());
  const int nt = threads();
  const double dmax = d == 2        ? prepare_terms<2, kPacked2>(B, coef, m_, nt)
                      : &layout_for(d, normals, simd_) == &kPacked3 ? prepare_terms<3, kPacked3>(B, coef, m_, nt)
                                    : prepare_terms<3, kPairs>(B, coef, m_, nt);
  // sigma = 2^-e with dmax in [2^(e-1), 2^e): normals scale D by it (exact), so that cof(D) neither
  // underflows nor overflows in float for models of any size float can hold.
  int ex = 0;
  if (std::isfinite(dmax) && dmax > 0) std::frexp(dmax, &ex);
  dscale_ = static_cast<float>(std::ldexp(1.0, std::clamp(-ex, -126, 126)));
}

// The rest-normal block is read 12 bytes a point in step with the two outputs written 12 bytes a
// point. When the block starts just before an output modulo 4 KiB (or at the same offset, as
// large blocks that are all page-aligned alike do), each load finds a recent store with the same
// low 12 address bits and waits on it ("4K aliasing"; 1.3x the time of the whole pass measured
// on this project's Zen 4 machine). So (block - output) modulo 4 KiB is kept within [lo, 3072]
// bytes for both outputs: stores up to 1024 bytes behind the loads are clear of them (the AVX2
// kernel's normals lag 8 points, 96 bytes; the AVX-512 kernel's m loads and normal stores lag
// the positions by 16 to 32 points), and stores ahead of them by less than lo: 64 bytes for the
// AVX2 kernel, 384 (32 points) for the AVX-512 one, whose m loads for a group of 16 come after
// the positions of up to 24 points more were stored. The block is moved once when an output
// buffer first breaks that, then never again for the same buffers; callers that alternate
// buffers needing different places get at most two moves, then the block stays where it is (a
// slower pass, not a copy every frame).
const float* FastEvaluator::rest_normals_for(const float* positions, const float* normals) {
  const std::uintptr_t lo = simd_ == Simd::Avx512 ? 384 : 64;
  auto clear = [&](std::size_t off) {
    const auto at = reinterpret_cast<std::uintptr_t>(normals_.data() + off);
    for (const float* out : {positions, normals}) {
      const std::uintptr_t gap = (at - reinterpret_cast<std::uintptr_t>(out)) % 4096;
      if (gap < lo || gap > 4096 - 1024) return false;
    }
    return true;
  };
  if (!clear(moff_) && moves_ < 2) {
    ++moves_;
    std::size_t off = 0;
    while (off + 4 < kSlack && !clear(off)) off += 4;  // exists: each output rules out at most 1408 of 4096 bytes
    std::memmove(normals_.data() + off, normals_.data() + moff_, (static_cast<size_t>(p_) * d_ + 4) * sizeof(float));
    moff_ = off;
  }
  return normals_.data() + moff_;
}

void FastEvaluator::evaluate(const BezierPoints& B, RowMatrixXf& positions) {
  if (positions.rows() != p_ || positions.cols() != d_) positions.resize(p_, d_);
  evaluate(B, positions.data(), nullptr);
}

void FastEvaluator::evaluate(const BezierPoints& B, RowMatrixXf& positions, RowMatrixXf& normals) {
  if (positions.rows() != p_ || positions.cols() != d_) positions.resize(p_, d_);
  if (normals.rows() != p_ || normals.cols() != d_) normals.resize(p_, d_);
  evaluate(B, positions.data(), normals.data());
}

void FastEvaluator::evaluate(const BezierPoints& B, float* positions, float* normals) {
  const bool with_normals = normals != nullptr;
  prepare(B, with_normals);
  if (p_ == 0) return;
  const std::int32_t* rec = records_.data();
  const float* coef = align64(coef_.data());
  const float* mrest = with_normals ? rest_normals_for(positions, normals) : nullptr;
  const float sigma = dscale_;
  const int d = d_;
  const long long p = p_;
  const Layout& L = layout_for(d, with_normals, simd_);
#ifdef MBI_FAST_X86
  // sigma within 2^+-16 leaves |cof(D) m|^2 within 2^+-64 (m: [0.5, 1)): no scaling needed
  const KernelX86 x86 = simd_ == Simd::Avx512 || simd_ == Simd::Avx2
                            ? pick_x86(simd_, with_normals, !(sigma >= 0x1p-16f && sigma <= 0x1p16f), !coherent_)
                            : nullptr;
#endif
  auto run = [&](long long begin, long long end) {
#ifdef MBI_FAST_X86
    if (x86) {
      const long long mid = begin + (end - begin) / 4 * 4;
      x86(rec, coef, mrest, sigma, positions, normals, begin, mid);
      begin = mid;  // the last 1-3 points of the range: portably, exact-size stores
    }
#endif
    if (d == 3) eval_scalar<3>(rec, coef, L, mrest, sigma, positions, normals, begin, end);
    else eval_scalar<2>(rec, coef, L, mrest, sigma, positions, normals, begin, end);
  };
  const int nt = threads();
  if (nt <= 1) {
    run(0, p);
    return;
  }
#ifdef _OPENMP
  // Blocks handed out as threads free up rather than one fixed share a thread: on a machine whose
  // cores are shared (a VM's vCPUs), a slowed core no longer holds the others back at the join.
  // kBlock points a block, a multiple of 4 (each block's first output float stays 16-byte aligned).
  const long long blocks = (p + kBlock - 1) / kBlock;
#pragma omp parallel for schedule(dynamic, 1) num_threads(nt)
  for (long long b = 0; b < blocks; ++b) run(b * kBlock, std::min(p, (b + 1) * kBlock));
#endif
}

}  // namespace mbi::interp
