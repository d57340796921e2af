// The portable evaluation kernel (see fast_kernel.hpp): plain C++, any CPU, 2D and 3D, either
// layout, rows in order or scattered; also the tails of the x86 kernels' ranges.
#include "evaluate/fast_kernel.hpp"

#include <cfloat>
#include <cmath>
#include <cstring>

namespace mbi::interp::detail {
namespace {

float as_float(std::int32_t w) {
  float f;
  std::memcpy(&f, &w, sizeof f);
  return f;
}

// x = (c_0 + b_1 t_1) + (b_2 t_2 + .. + b_d t_d), summed in this order by every kernel (so that
// a positions-only call and a call with normals give the same positions).
template <int D>
void eval_d(const std::int32_t* rec, const float* coef, std::int32_t ebase, const Layout& L, const float* mrest,
            float sigma, float* pos, float* nout, const std::int32_t* row, long long begin, long long end) {
  constexpr int NC = coef_stride(D);
  constexpr TermIndex ix(D);
  for (long long p = begin; p < end; ++p) {
    const std::int32_t* r = rec + p * (D + 1);
    const long long out = row ? row[p] : p;  // the point's output row
    const long long e = static_cast<long long>(r[0]) - ebase;
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
    for (int c = 0; c < D; ++c) pos[out * D + c] = x[c];
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
    // 0 where J is singular: the x86 kernels' threshold, so that all give the same points 0
    for (int c = 0; c < D; ++c) nout[out * D + c] = sq > FLT_MIN ? o[c] / len : 0.0f;
  }
}

}  // namespace

void eval_portable(int d, const std::int32_t* rec, const float* coef, std::int32_t ebase, const Layout& L,
                   const float* mrest, float sigma, float* pos, float* nout, const std::int32_t* row, long long begin,
                   long long end) {
  if (d == 3) eval_d<3>(rec, coef, ebase, L, mrest, sigma, pos, nout, row, begin, end);
  else eval_d<2>(rec, coef, ebase, L, mrest, sigma, pos, nout, row, begin, end);
}

}  // namespace mbi::interp::detail
