// The AVX-512 evaluation kernels (see fast_kernel.hpp): two points to a 512-bit vector, each as
// in the AVX2 positions kernel (pairs layout), positions only (eval_positions) and with normals
// (eval_normals); prefetches and stores (streaming, or scattered rows) as in the AVX2 kernels.
#include "evaluate/fast_kernel_x86.hpp"

#ifdef MBI_INTERP_X86
#include <cfloat>
#include <initializer_list>

// GCC 12's AVX-512 intrinsics fill unused lanes from _mm512_undefined_*() and then warn that
// they may be (or are) used uninitialized (GCC bug 105593); no lane of those is ever read here.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"

namespace mbi::interp::detail {
namespace {

// 8 floats at A + k (low half) and at B + k (high half), 32-byte aligned
MBI_TARGET_AVX512 inline __m512 halves(const float* A, const float* B, int k) {
  return _mm512_insertf32x8(_mm512_castps256_ps512(_mm256_load_ps(A + k)), _mm256_load_ps(B + k), 1);
}

#define MBI_SWAP512(v) _mm512_shuffle_f32x4((v), (v), _MM_SHUFFLE(2, 3, 0, 1))  // the 128-bit halves of each 256
#define MBI_YZX512(v) _mm512_permute_ps((v), _MM_SHUFFLE(3, 0, 2, 1))

// Index vectors of the 512-bit kernels (loaded once per call).
struct Idx512 {
  __m512i rot, out;
  MBI_TARGET_AVX512 Idx512()
      : rot(_mm512_setr_epi32(0, 1, 2, 3, 1, 2, 3, 0, 4, 5, 6, 7, 5, 6, 7, 4)),
        out(_mm512_setr_epi32(0, 1, 2, 8, 9, 10, 16, 17, 18, 24, 25, 26, 0, 0, 0, 0)) {}
};

// Two points whose records start at r (A in the low 256 bits, B in the high), pairs layout: each
// half computes what the AVX2 positions kernel computes for a point (one_point in
// fast_kernel_avx2.cpp), in the same order (masks for its blends). Returns
// (x_A, ., x_B, .) in 128-bit lanes 0 and 2. With Derivs also X = (D_1 | D_2) and Ad = (. | D_3)
// in each point's 256 bits (D_k = dx/db_k; summed in another order than the packed kernel's).
template <bool Derivs>
MBI_TARGET_AVX512 inline __m512 pair512(const std::int32_t* r, const float* coef, std::int32_t ebase, const Idx512& I,
                                        __m512& X, __m512& Ad) {
  constexpr int NC = coef_stride(3);
  const float* A = coef + (static_cast<long long>(r[0]) - ebase) * NC;
  const float* B = coef + (static_cast<long long>(r[4]) - ebase) * NC;
  const __m512 v = _mm512_castps256_ps512(_mm256_loadu_ps(reinterpret_cast<const float*>(r)));
  const __m512 L0 = halves(A, B, 0), L1 = halves(A, B, 8), L2 = halves(A, B, 16), L3 = halves(A, B, 24);
  // (rA, rA' | rB, rB'), r' = (b1, b2, b3, e): one cross-lane permute, then every coefficient
  // vector by an in-lane one with the same pattern in each 128-bit lane (twice the throughput)
  const __m512 v2 = _mm512_permutexvar_ps(I.rot, v);
  const __m512 b12 = _mm512_permute_ps(v2, 0x55), b23 = _mm512_permute_ps(v2, 0xAA);
  const __m512 b3lo = _mm512_maskz_permute_ps(0x0F0F, v2, 0xFF), b3hi = _mm512_maskz_permute_ps(0xF0F0, v2, 0xAA);
  const __m512 ob3 = _mm512_mask_permute_ps(_mm512_set1_ps(1.0f), 0xF0F0, v2, 0xAA);
  // (c0 | c3) from the slots' 4th floats, as in one_point
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
    // chain waits on the other (deriving (D_2 | D_3) from X through a swap and blends would).
    X = _mm512_mask3_fmadd_ps(MBI_SWAP512(L2), b1hi, _mm512_fmadd_ps(L1, b12, T), 0xF0F0);
    // (. | t3 + b3 c33 + b2 c23 + b1 c13) = (. | D3)
    Ad = _mm512_fmadd_ps(MBI_SWAP512(L3), b1hi, _mm512_fmadd_ps(L2, b12, _mm512_fmadd_ps(L3, b3hi, U)));
  }
  return _mm512_add_ps(V, MBI_SWAP512(V));  // (c0 + b1 t1) + (b2 t2 + b3 t3)
}

// Points p .. p + 3 from two pair512 results to their rows of out: in order (3 stores at row p)
// or scattered (row[p + k]).
template <bool Scatter>
MBI_TARGET_AVX512 inline void store4(float* out, const std::int32_t* row, long long p, bool aligned, const Idx512& I,
                                     __m512 W0, __m512 W1) {
  if constexpr (Scatter) {
    scatter4(out, row + p, _mm512_castps512_ps128(W0), _mm512_extractf32x4_ps(W0, 2), _mm512_castps512_ps128(W1),
             _mm512_extractf32x4_ps(W1, 2));
  } else {
    const __m512 o = _mm512_permutex2var_ps(W0, I.out, W1);
    store12(out + 3 * p, aligned, _mm512_castps512_ps128(o), _mm512_extractf32x4_ps(o, 1), _mm512_extractf32x4_ps(o, 2));
  }
}

// The 4 points (x, y, z, .) in the 128-bit lanes of v to their rows out + 3 row[k].
MBI_TARGET_AVX512 inline void scatter_lanes(float* out, const std::int32_t* row, __m512 v) {
  scatter4(out, row, _mm512_castps512_ps128(v), _mm512_extractf32x4_ps(v, 1), _mm512_extractf32x4_ps(v, 2),
           _mm512_extractf32x4_ps(v, 3));
}

// Positions only, pairs layout, two points to a 512-bit vector, 4 points an iteration.
template <bool Prefetch, bool Scatter>
MBI_TARGET_AVX512 void eval_positions(const std::int32_t* rec, const float* coef, std::int32_t ebase, const float*,
                                      float, float* pos, float*, const std::int32_t* row, long long begin,
                                      long long end) {
  const Idx512 I;
  const bool aligned = reinterpret_cast<std::uintptr_t>(pos + 3 * begin) % 16 == 0;
  __m512 none;
  for (long long p = begin; p < end; p += 4) {
    prefetch_at(rec + 4 * p, 4LL * 4 * kStreamAhead);
    if constexpr (Prefetch) prefetch_terms(rec, coef, ebase, p);
    if constexpr (Scatter) prefetch_rows(row, pos, nullptr, p);
    const __m512 W0 = pair512<false>(rec + 4 * p, coef, ebase, I, none, none);
    const __m512 W1 = pair512<false>(rec + 4 * (p + 2), coef, ebase, I, none, none);
    store4<Scatter>(pos, row, p, aligned, I, W0, W1);
  }
  _mm_sfence();
}

// o / |o| for the 4 vectors of o (lane 3 of each 0; 0 where |o|^2 <= FLT_MIN: J singular).
MBI_TARGET_AVX512 inline __m512 renormalise512(__m512 o) {
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
MBI_TARGET_AVX512 inline __m512 normals4(const __m512* X, const __m512* Ad, __m512 M, __m512 sig) {
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
MBI_TARGET_AVX512 inline Soa3 to_soa(__m512 P0, __m512 P1, __m512 P2, __m512 P3) {
  const __m512 t0 = _mm512_unpacklo_ps(P0, P1), t1 = _mm512_unpackhi_ps(P0, P1);
  const __m512 t2 = _mm512_unpacklo_ps(P2, P3), t3 = _mm512_unpackhi_ps(P2, P3);
  return {_mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0)), _mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2)),
          _mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0))};
}

// Constants of Normals16: which 128-bit lanes to merge.
struct Idx16 {
  __m512i lo, hi;
  MBI_TARGET_AVX512 Idx16()
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
  MBI_TARGET_AVX512 static void gather4(const __m512* X, const __m512* Ad, const Idx16& I, __m512* G) {
    G[0] = _mm512_permutex2var_ps(X[0], I.lo, X[1]);
    G[1] = _mm512_permutex2var_ps(X[0], I.hi, X[1]);
    G[2] = _mm512_permutex2var_ps(Ad[0], I.hi, Ad[1]);
  }
  // 1: D_1, D_2 and D_3 of the 16 points (G[3 j + k]: D_(k+1) of points 4 j .. 4 j + 3)
  MBI_TARGET_AVX512 void phase1(const __m512* G) {
    D1 = to_soa(G[0], G[3], G[6], G[9]);
    D2 = to_soa(G[1], G[4], G[7], G[10]);
    D3 = to_soa(G[2], G[5], G[8], G[11]);
  }
  // 2: the scale, m (48 floats at mr)
  template <bool Scaled>
  MBI_TARGET_AVX512 void phase2(const float* mr, __m512 sig) {
    if constexpr (Scaled)
      for (Soa3* D : {&D1, &D2, &D3})
        D->x = _mm512_mul_ps(sig, D->x), D->y = _mm512_mul_ps(sig, D->y), D->z = _mm512_mul_ps(sig, D->z);
    m1 = _mm512_loadu_ps(mr), m2 = _mm512_loadu_ps(mr + 16), m3 = _mm512_loadu_ps(mr + 32);
  }
  // 3: E = m1 D3 - m3 D1, w = D2 x E + m2 (D3 x D1), renormalised (0 where |w|^2 <= FLT_MIN)
  MBI_TARGET_AVX512 void phase3() {
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
  // 4: to the rows of points p .. p + 15 of out (in order: 48 floats at row p; scattered: rows
  // row[p + k]), point 4 k + g's vector from lane 4 g + k
  template <bool Scatter>
  MBI_TARGET_AVX512 void phase4(float* out, const std::int32_t* row, long long p, bool aligned) const {
    const __m512 zero = _mm512_setzero_ps();
    const __m512 u0 = _mm512_unpacklo_ps(wx, wy), u1 = _mm512_unpackhi_ps(wx, wy);
    const __m512 v0 = _mm512_unpacklo_ps(wz, zero), v1 = _mm512_unpackhi_ps(wz, zero);
    const __m512 Q[4] = {_mm512_shuffle_ps(u0, v0, _MM_SHUFFLE(1, 0, 1, 0)), _mm512_shuffle_ps(u0, v0, _MM_SHUFFLE(3, 2, 3, 2)),
                         _mm512_shuffle_ps(u1, v1, _MM_SHUFFLE(1, 0, 1, 0)), _mm512_shuffle_ps(u1, v1, _MM_SHUFFLE(3, 2, 3, 2))};
    [[maybe_unused]] const __m512i pack = _mm512_setr_epi32(0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, 0, 0, 0, 0);
    for (int k = 0; k < 4; ++k) {  // Q[k]: points 4 k .. 4 k + 3 as (x, y, z, 0)
      if constexpr (Scatter) {
        scatter_lanes(out, row + p + 4 * k, Q[k]);
      } else {
        const __m512 n = _mm512_permutexvar_ps(pack, Q[k]);
        store12(out + 3 * (p + 4 * k), aligned, _mm512_castps512_ps128(n), _mm512_extractf32x4_ps(n, 1),
                _mm512_extractf32x4_ps(n, 2));
      }
    }
  }
};

// Positions and normals, pairs layout, two points to a 512-bit vector, 16 points an iteration:
// the positions 4 at a time (exactly as eval_positions), and after each group of 4 one phase
// of the normals of the 16 points before (Normals16), then the last groups of 4 (normals4). No
// scratch block: each group's derivatives go, one point to a 128-bit lane, into 12 registers
// (gather4), which phase 1 of the next group reads whole before they are overwritten (no copy
// between groups; the compiler spills some to the stack). A block of derivatives for 128 points
// cost more in L1 misses (its lines evicted by the element terms of random points) and 4K
// aliasing than the normals themselves.
template <bool Scaled, bool Prefetch, bool Scatter>
MBI_TARGET_AVX512 void eval_normals(const std::int32_t* rec, const float* coef, std::int32_t ebase, const float* mrest,
                                    float sigma, float* pos, float* nout, const std::int32_t* row, long long begin,
                                    long long end) {
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
      if constexpr (Prefetch) prefetch_terms(rec, coef, ebase, g);
      if constexpr (Scatter) prefetch_rows(row, pos, nout, g);
      const __m512 W0 = pair512<true>(rec + 4 * g, coef, ebase, I, X[0], Ad[0]);
      const __m512 W1 = pair512<true>(rec + 4 * (g + 2), coef, ebase, I, X[1], Ad[1]);
      store4<Scatter>(pos, row, g, aligned, I, W0, W1);
      if (prev) {  // phase 1 reads all of the previous group's G before gather4 overwrites it
        if (q == 0) N.phase1(G);
        if (q == 1) N.phase2<Scaled>(mrest + 3 * (p - 16), sig);
        if (q == 2) N.phase3();
        if (q == 3) N.phase4<Scatter>(nout, row, p - 16, aligned);
      }
      Normals16::gather4(X, Ad, I16, G + 3 * q);
    }
  }
  if (p > begin) {
    N.phase1(G);
    N.phase2<Scaled>(mrest + 3 * (p - 16), sig);
    N.phase3();
    N.phase4<Scatter>(nout, row, p - 16, aligned);
  }
  [[maybe_unused]] const __m512i pack = _mm512_setr_epi32(0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, 0, 0, 0, 0);
  for (; p < end; p += 4) {
    const __m512 W0 = pair512<true>(rec + 4 * p, coef, ebase, I, X[0], Ad[0]);
    const __m512 W1 = pair512<true>(rec + 4 * (p + 2), coef, ebase, I, X[1], Ad[1]);
    store4<Scatter>(pos, row, p, aligned, I, W0, W1);
    const __m512 n4 = normals4<Scaled>(X, Ad, _mm512_loadu_ps(mrest + 3 * p), sig);
    if constexpr (Scatter) {
      scatter_lanes(nout, row + p, n4);
    } else {
      const __m512 n = _mm512_permutexvar_ps(pack, n4);
      store12(nout + 3 * p, aligned, _mm512_castps512_ps128(n), _mm512_extractf32x4_ps(n, 1), _mm512_extractf32x4_ps(n, 2));
    }
  }
  _mm_sfence();
}

}  // namespace

const KernelTable avx512_kernels = {
    {{eval_positions<false, false>, eval_positions<false, true>}, {eval_positions<true, false>, eval_positions<true, true>}},
    {{eval_normals<false, false, false>, eval_normals<false, false, true>},
     {eval_normals<false, true, false>, eval_normals<false, true, true>}},
    {{eval_normals<true, false, false>, eval_normals<true, false, true>},
     {eval_normals<true, true, false>, eval_normals<true, true, true>}},
};

}  // namespace mbi::interp::detail
#pragma GCC diagnostic pop
#endif
