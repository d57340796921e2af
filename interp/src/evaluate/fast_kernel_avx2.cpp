// The AVX2 evaluation kernels (see fast_kernel.hpp), FMA on 256-bit vectors: positions only
// (pairs layout, eval_positions: one point and two terms to a vector, 4 aligned 32-byte loads a
// point) and positions with normals (packed layout, eval_normals: two points to a vector
// (x, y, z, * | x, y, z, *), each term loaded 16 bytes at a time). An element's 2 cache lines are
// prefetched kPrefetch points ahead when the points are not stored coherently (random points
// read the terms from L2, not L1; in a mesh's order the prefetches only cost); the input streams
// (records, rest normals) are prefetched kStreamAhead points ahead in either order. Groups of 4
// points are written as 3 aligned 16-byte vectors with streaming stores (the output is not read
// back by this pass, so it bypasses the caches and saves the write-allocate reads); rows
// scattered by a permutation take 12-byte stores, their lines prefetched kRowAhead points ahead.
#include "evaluate/fast_kernel_x86.hpp"

#ifdef MBI_INTERP_X86
#include <cfloat>

namespace mbi::interp::detail {
namespace {

// term k of elements A (low half) and B (high half)
MBI_TARGET_AVX2 inline __m256 term2(const float* A, const float* B, int k) {
  return _mm256_loadu2_m128(B + 3 * k, A + 3 * k);
}

#define MBI_YZX(v) _mm256_permute_ps((v), _MM_SHUFFLE(3, 0, 2, 1))

// Positions of the 2 points whose records start at r (packed layout) and their derivatives
// D_k = dx/db_k (times sigma when Scaled: of order 1 at any model scale; cof(D) is quadratic in D).
template <bool Scaled>
MBI_TARGET_AVX2 inline void two_points(const std::int32_t* r, const float* coef, std::int32_t ebase, __m256 sigma,
                                       __m256& x, __m256* D) {
  constexpr int NC = coef_stride(3);
  const __m256 v = _mm256_loadu_ps(reinterpret_cast<const float*>(r));
  const float* A = coef + (static_cast<long long>(r[0]) - ebase) * NC;
  const float* B = coef + (static_cast<long long>(r[4]) - ebase) * NC;
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
MBI_TARGET_AVX2 inline __m256 cof_times(const __m256* D, __m256 m) {
  const __m256 Y1 = MBI_YZX(D[0]), Y2 = MBI_YZX(D[1]), Y3 = MBI_YZX(D[2]);
  // a x b = (a * b.yzx - a.yzx * b).yzx; the last shuffle is linear, so it is applied once.
  __m256 o = _mm256_mul_ps(_mm256_permute_ps(m, 0x00), _mm256_fmsub_ps(D[1], Y3, _mm256_mul_ps(Y2, D[2])));
  o = _mm256_fmadd_ps(_mm256_permute_ps(m, 0x55), _mm256_fmsub_ps(D[2], Y1, _mm256_mul_ps(Y3, D[0])), o);
  o = _mm256_fmadd_ps(_mm256_permute_ps(m, 0xAA), _mm256_fmsub_ps(D[0], Y2, _mm256_mul_ps(Y1, D[1])), o);
  return _mm256_blend_ps(MBI_YZX(o), _mm256_setzero_ps(), 0x88);
}

// o / |o| for the 2 vectors of o (0 where |o|^2 <= FLT_MIN: J singular).
MBI_TARGET_AVX2 inline __m256 renormalise(__m256 o) {
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
MBI_TARGET_AVX2 inline void pack4(__m128 r0, __m128 r1, __m128 r2, __m128 r3, __m128& o0, __m128& o1, __m128& o2) {
  o0 = _mm_blend_ps(r0, _mm_shuffle_ps(r1, r1, _MM_SHUFFLE(0, 0, 0, 0)), 0x8);
  o1 = _mm_shuffle_ps(r1, r2, _MM_SHUFFLE(1, 0, 2, 1));
  o2 = _mm_blend_ps(_mm_shuffle_ps(r3, r3, _MM_SHUFFLE(2, 1, 0, 0)),
                    _mm_shuffle_ps(r2, r2, _MM_SHUFFLE(2, 2, 2, 2)), 0x1);
}

// The results (x, y, z, *) of points p .. p + 3 to their rows of out: in order (3 16-byte
// stores at row p) or scattered (row[p + k]).
template <bool Scatter>
MBI_TARGET_AVX2 inline void put4(float* out, const std::int32_t* row, long long p, bool aligned, __m128 r0, __m128 r1,
                                 __m128 r2, __m128 r3) {
  if constexpr (Scatter) {
    scatter4(out, row + p, r0, r1, r2, r3);
  } else {
    __m128 o0, o1, o2;
    pack4(r0, r1, r2, r3, o0, o1, o2);
    store12(out + 3 * p, aligned, o0, o1, o2);
  }
}

// the same, two results to a vector
template <bool Scatter>
MBI_TARGET_AVX2 inline void put4(float* out, const std::int32_t* row, long long p, bool aligned, __m256 a, __m256 b) {
  put4<Scatter>(out, row, p, aligned, _mm256_castps256_ps128(a), _mm256_extractf128_ps(a, 1),
                _mm256_castps256_ps128(b), _mm256_extractf128_ps(b, 1));
}

// Positions and normals, packed layout, points [begin, end) with end - begin a multiple of 4 (the
// caller runs the rest portably). The work of 4 points runs in three stages over three
// iterations: positions and D (this group), cof(D) m (the group before), renormalisation (the
// one before that). Each stage is a long chain of dependent operations; in one iteration they
// starve the out-of-order window, staggered they overlap.
template <bool Scaled, bool Prefetch, bool Scatter>
MBI_TARGET_AVX2 void eval_normals(const std::int32_t* rec, const float* coef, std::int32_t ebase, const float* mrest,
                                  float sigma, float* pos, float* nout, const std::int32_t* row, long long begin,
                                  long long end) {
  const __m256 sig = _mm256_set1_ps(sigma);
  const bool aligned = reinterpret_cast<std::uintptr_t>(pos + 3 * begin) % 16 == 0 &&
                       reinterpret_cast<std::uintptr_t>(nout + 3 * begin) % 16 == 0;
  const __m256 zero = _mm256_setzero_ps();
  // D and m of the group at p - 4, cof(D) m of the group at p - 8 (two vectors each)
  __m256 D[2][3] = {{zero, zero, zero}, {zero, zero, zero}}, m[2] = {zero, zero}, o[2] = {zero, zero};
  long long p = begin;
  for (; p < end; p += 4) {
    prefetch_at(rec + 4 * p, 4LL * 4 * kStreamAhead);  // one 64-byte line of records per 4 points
    prefetch_at(mrest + 3 * p, 4LL * 3 * kStreamAhead);
    if constexpr (Prefetch) prefetch_terms(rec, coef, ebase, p);
    if constexpr (Scatter) prefetch_rows(row, pos, nout, p);
    // stages 3 and 2 (on zeros in the first two iterations: not stored)
    const __m256 n0 = renormalise(o[0]), n1 = renormalise(o[1]);
    o[0] = cof_times(D[0], m[0]);
    o[1] = cof_times(D[1], m[1]);
    __m256 x0, x1;
    two_points<Scaled>(rec + 4 * p, coef, ebase, sig, x0, D[0]);
    two_points<Scaled>(rec + 4 * (p + 2), coef, ebase, sig, x1, D[1]);
    put4<Scatter>(pos, row, p, aligned, x0, x1);
    m[0] = _mm256_loadu2_m128(mrest + 3 * (p + 1), mrest + 3 * p);
    m[1] = _mm256_loadu2_m128(mrest + 3 * (p + 3), mrest + 3 * (p + 2));
    if (p - begin >= 8) put4<Scatter>(nout, row, p - 8, aligned, n0, n1);
  }
  // the last two groups: o holds the one at p - 8, D and m the one at p - 4
  if (p - begin >= 8) put4<Scatter>(nout, row, p - 8, aligned, renormalise(o[0]), renormalise(o[1]));
  if (p - begin >= 4)
    put4<Scatter>(nout, row, p - 4, aligned, renormalise(cof_times(D[0], m[0])), renormalise(cof_times(D[1], m[1])));
  _mm_sfence();
}

// Positions only, pairs layout: one point to a 256-bit vector, two terms to it, the element's
// 128 bytes read with 4 aligned 32-byte loads (the packed layout needs 20 16-byte loads for 2
// points, most of them straddling 16-byte boundaries).
//   T = (c1 | c2) + (b1 | b2)(c11 | c22) + (b2 | b3)(c12 | c23) + (b3 | 0)(c13 | c33) = (t1 | t2)
//   U = (c0 | c3) + (0 | b3)(c13 | c33) = (c0 | t3)
//   x = lo + hi of (b1 | b2) T + (1 | b3) U = (c0 + b1 t1) + (b2 t2 + b3 t3)
MBI_TARGET_AVX2 inline __m128 one_point(const float* C, const std::int32_t* r, __m256i sel12, __m256i sel23) {
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

template <bool Prefetch, bool Scatter>
MBI_TARGET_AVX2 void eval_positions(const std::int32_t* rec, const float* coef, std::int32_t ebase, const float*, float,
                                    float* pos, float*, const std::int32_t* row, long long begin, long long end) {
  constexpr int NC = coef_stride(3);
  const __m256i sel12 = _mm256_setr_epi32(1, 1, 1, 1, 2, 2, 2, 2), sel23 = _mm256_setr_epi32(2, 2, 2, 2, 3, 3, 3, 3);
  const bool aligned = reinterpret_cast<std::uintptr_t>(pos + 3 * begin) % 16 == 0;
  for (long long p = begin; p < end; p += 4) {
    prefetch_at(rec + 4 * p, 4LL * 4 * kStreamAhead);
    if constexpr (Prefetch) prefetch_terms(rec, coef, ebase, p);
    if constexpr (Scatter) prefetch_rows(row, pos, nullptr, p);
    __m128 x[4];
    for (int k = 0; k < 4; ++k) {
      const std::int32_t* r = rec + 4 * (p + k);
      x[k] = one_point(coef + (static_cast<long long>(r[0]) - ebase) * NC, r, sel12, sel23);
    }
    put4<Scatter>(pos, row, p, aligned, x[0], x[1], x[2], x[3]);
  }
  _mm_sfence();
}

}  // namespace

const KernelTable avx2_kernels = {
    {{eval_positions<false, false>, eval_positions<false, true>}, {eval_positions<true, false>, eval_positions<true, true>}},
    {{eval_normals<false, false, false>, eval_normals<false, false, true>},
     {eval_normals<false, true, false>, eval_normals<false, true, true>}},
    {{eval_normals<true, false, false>, eval_normals<true, false, true>},
     {eval_normals<true, true, false>, eval_normals<true, true, true>}},
};

}  // namespace mbi::interp::detail
#endif
