#pragma once
// The evaluation kernels of FastEvaluator (internal): the element terms fast_evaluate.cpp writes
// and the kernels read, and the kernels, one file an instruction set (fast_kernel_portable.cpp,
// fast_kernel_avx2.cpp, fast_kernel_avx512.cpp).
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
#include "runtime/cpu.hpp"

#include <mbi/interp/modified_bi.hpp>

#include <Eigen/Core>

#include <cstdint>

namespace mbi::interp::detail {

// Per element, the position polynomial's terms (d floats each) padded to whole cache lines (3D:
// 10 x 3 = 30 floats in 32, 128 B: 2 lines, 64-byte aligned), in one of two layouts (Layout).
constexpr int position_terms(int d) { return 1 + d * (d + 3) / 2; }  // 10 in 3D, 6 in 2D
constexpr int coef_stride(int d) { return d == 3 ? 32 : 16; }
static_assert(position_terms(3) * 3 + 1 <= coef_stride(3) && position_terms(2) * 2 <= coef_stride(2));

// Records past the last point (element 0): the x86 kernels prefetch the terms of the point
// kPrefetch ahead without a bounds check (their addresses computed as integers: over a block of
// terms, ebase > 0, those elements may lie outside it).
constexpr int kPrefetch = 16;
// Rows past the last of a permutation (row 0): the x86 kernels that scatter prefetch the output
// rows of the point kRowAhead ahead without a bounds check.
constexpr int kRowAhead = 32;

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
//   x86 kernels with 4 aligned 256-bit loads: (c1 | c2), (c11 | c22), (c12 | c23), (c13 | c33),
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
inline constexpr Layout kPairs = {{3, 0, 8, 16, 24, 4, 12, 20, 7, 28}, {8, 1, 1, 1, 1, 1, 1, 1, 8, 1}};
inline constexpr Layout kPacked2 = packed_layout(2), kPacked3 = packed_layout(3);

// A kernel: positions (and normals when nout is set) of records [begin, end) from the records
// (rec: (d+1) words a point), the element terms (coef, coef_stride(d) floats an element, 64-byte
// aligned; element e's at coef + (e - ebase) coef_stride(d): ebase is 0 for the whole table, the
// first element of a block of terms otherwise), the rest normals' m (mrest, one per record) and
// the scale sigma of the derivatives. Record p's results go to output row row[p] (scattered), or
// to row p where row is nullptr.
using Kernel = void (*)(const std::int32_t* rec, const float* coef, std::int32_t ebase, const float* mrest, float sigma,
                        float* pos, float* nout, const std::int32_t* row, long long begin, long long end);

// The 3D element terms of B in the pairs layout (m x coef_stride(3) floats at coef, 64-byte
// aligned), on up to `threads` threads; returns the largest |c_k| (fast_evaluate.cpp).
double pairs_terms3(const MatrixIn& B, float* coef, int m, int threads);

// The portable loop (d = 2 or 3, terms in layout L), any number of points.
void eval_portable(int d, const std::int32_t* rec, const float* coef, std::int32_t ebase, const Layout& L,
                   const float* mrest, float sigma, float* pos, float* nout, const std::int32_t* row, long long begin,
                   long long end);

#ifdef MBI_INTERP_X86
// The 3D kernels of an instruction set: [positions only, normals, normals with D scaled]
// [without, with prefetches of the element terms][rows in order, scattered]. They take
// end - begin a multiple of 4 (the caller runs the rest portably) and read the pairs layout, or
// with AVX2 and normals the packed one.
using KernelTable = Kernel[3][2][2];
extern const KernelTable avx2_kernels, avx512_kernels;
#endif

}  // namespace mbi::interp::detail
