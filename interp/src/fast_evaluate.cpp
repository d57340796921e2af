// The compact float evaluation kernel (see fast_evaluate.hpp).
//
// Each element's quadratic Bezier simplex sum_k b_k^2 P_k + sum_{i<j} 2 b_i b_j P_ij is rewritten,
// with b_0 = 1 - b_1 - ... - b_d, as a polynomial in (b_1..b_d):
//   x = c_0 + sum_k b_k c_k + sum_{k<=l} b_k b_l c_kl
//   c_0 = P_0, c_k = 2 (P_0k - P_0), c_kk = P_0 + P_k - 2 P_0k,
//   c_kl = 2 (P_0 - P_0k - P_0l + P_kl) (k < l),
// evaluated in Horner form x = c_0 + sum_k b_k (c_k + sum_{l>=k} b_l c_kl): in 3D 9 FMAs on
// 4-float vectors (x, y, z, 0) a point. For normals, J = dx/du = sum_k (dx/db_k) a_k^T is linear in
// b: column r of J is J0_r + sum_l b_l J_lr with J0_r = sum_k a_k[r] c_k and
// J_lr = sum_k a_k[r] e_kl (e_kl = c_kl for k != l, 2 c_kk for k = l); the mapped normal is
// cof(J) n = n_0 (j_1 x j_2) + n_1 (j_2 x j_0) + n_2 (j_0 x j_1) (fact 6).
//
// The coefficients are computed in double from B and rounded to float once per call.
#include <mbi/interp/fast_evaluate.hpp>

#include "cpu.hpp"

#include "detail.hpp"

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

// Per element, the position polynomial's terms (d floats each, packed) padded to whole cache
// lines (3D: 10 x 3 = 30 floats in 32, 128 B: 2 lines, 64-byte aligned; the x86 kernel loads 4
// floats at each term and ignores the 4th), and likewise the Jacobian's (3D: 12 x 3 in 48).
constexpr int position_terms(int d) { return 1 + d * (d + 3) / 2; }  // 10 in 3D, 6 in 2D
constexpr int jacobian_terms(int d) { return d * (d + 1); }          // 12 in 3D, 6 in 2D
constexpr int coef_stride(int d) { return d == 3 ? 32 : 16; }
constexpr int jac_stride(int d) { return d == 3 ? 48 : 16; }
static_assert(position_terms(3) * 3 + 1 <= coef_stride(3) && jacobian_terms(3) * 3 + 1 <= jac_stride(3));
static_assert(position_terms(2) * 2 <= coef_stride(2) && jacobian_terms(2) * 2 <= jac_stride(2));

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

// [begin, end) of thread t of nt over p points, boundaries multiples of 4 points (so that each
// thread's first output float is 16-byte aligned when the base is).
[[maybe_unused]] void chunk(long long p, int t, int nt, long long& begin, long long& end) {
  const long long groups = (p + 3) / 4;
  begin = std::min(p, 4 * (groups * t / nt));
  end = std::min(p, 4 * (groups * (t + 1) / nt));
}

// ------------------------------------------------------------------------ portable kernel
template <int D>
void eval_scalar(const std::int32_t* rec, const float* coef, const float* jac, const float* nrest,
                 float* pos, float* nout, long long begin, long long end) {
  constexpr int NC = coef_stride(D), NJ = jac_stride(D);
  for (long long p = begin; p < end; ++p) {
    const std::int32_t* r = rec + p * (D + 1);
    const long long e = r[0];
    float b[D + 1];
    for (int k = 1; k <= D; ++k) b[k] = as_float(r[k]);
    const float* C = coef + e * NC;
    float x[D];
    for (int c = 0; c < D; ++c) x[c] = C[c];
    int s = 1;
    for (int k = 1; k <= D; ++k) {
      float t[D];
      for (int c = 0; c < D; ++c) t[c] = C[s * D + c];
      ++s;
      for (int l = k; l <= D; ++l, ++s)
        for (int c = 0; c < D; ++c) t[c] += b[l] * C[s * D + c];
      for (int c = 0; c < D; ++c) x[c] += b[k] * t[c];
    }
    for (int c = 0; c < D; ++c) pos[p * D + c] = x[c];
    if (!nout) continue;
    const float* G = jac + e * NJ;
    float J[D][D];  // J[c][r]: component c of column r
    for (int rr = 0; rr < D; ++rr) {
      const float* g = G + rr * (D + 1) * D;
      for (int c = 0; c < D; ++c) {
        float v = g[c];
        for (int l = 1; l <= D; ++l) v += b[l] * g[l * D + c];
        J[c][rr] = v;
      }
    }
    const float* n = nrest + p * D;
    float o[D];
    if constexpr (D == 3) {
      float Cm[3][3];
      for (int rr = 0; rr < 3; ++rr) {
        const int r1 = (rr + 1) % 3, r2 = (rr + 2) % 3;
        Cm[0][rr] = J[1][r1] * J[2][r2] - J[2][r1] * J[1][r2];
        Cm[1][rr] = J[2][r1] * J[0][r2] - J[0][r1] * J[2][r2];
        Cm[2][rr] = J[0][r1] * J[1][r2] - J[1][r1] * J[0][r2];
      }
      for (int c = 0; c < 3; ++c) o[c] = Cm[c][0] * n[0] + Cm[c][1] * n[1] + Cm[c][2] * n[2];
    } else {
      o[0] = J[1][1] * n[0] - J[1][0] * n[1];
      o[1] = -J[0][1] * n[0] + J[0][0] * n[1];
    }
    float len = 0;
    for (int c = 0; c < D; ++c) len += o[c] * o[c];
    len = std::sqrt(len);
    for (int c = 0; c < D; ++c) nout[p * D + c] = len > 0 ? o[c] / len : 0.0f;
  }
}

#ifdef MBI_FAST_X86
// ------------------------------------------------------------------------ x86 kernel (3D)
// 4-float vectors, FMA. Groups of 4 points are written as 3 aligned vectors (streaming stores:
// the output is not read back by this pass, so it bypasses the caches and saves the
// write-allocate reads).
#define MBI_TARGET __attribute__((target("avx2,fma")))

MBI_TARGET inline __m128 term(const float* C, int k) { return _mm_loadu_ps(C + 3 * k); }

MBI_TARGET inline __m128 position3(const float* C, __m128 b1, __m128 b2, __m128 b3) {
  __m128 t1 = _mm_fmadd_ps(term(C, 2), b1, term(C, 1));
  __m128 t2 = _mm_fmadd_ps(term(C, 6), b2, term(C, 5));
  const __m128 t3 = _mm_fmadd_ps(term(C, 9), b3, term(C, 8));
  t1 = _mm_fmadd_ps(term(C, 3), b2, t1);
  t2 = _mm_fmadd_ps(term(C, 7), b3, t2);
  t1 = _mm_fmadd_ps(term(C, 4), b3, t1);
  __m128 x = _mm_fmadd_ps(t1, b1, term(C, 0));
  x = _mm_fmadd_ps(t2, b2, x);
  return _mm_fmadd_ps(t3, b3, x);  // lane 3: not a coordinate (ignored by the stores)
}

#define MBI_YZX(v) _mm_shuffle_ps((v), (v), _MM_SHUFFLE(3, 0, 2, 1))

MBI_TARGET inline __m128 normal3(const float* G, __m128 b1, __m128 b2, __m128 b3, const float* n) {
  __m128 j[3];
  for (int r = 0; r < 3; ++r) {
    const float* g = G + r * 4 * 3;
    __m128 v = _mm_fmadd_ps(term(g, 1), b1, term(g, 0));
    v = _mm_fmadd_ps(term(g, 2), b2, v);
    j[r] = _mm_fmadd_ps(term(g, 3), b3, v);
  }
  const __m128 n0 = _mm_set1_ps(n[0]), n1 = _mm_set1_ps(n[1]), n2 = _mm_set1_ps(n[2]);
  const __m128 y0 = MBI_YZX(j[0]), y1 = MBI_YZX(j[1]), y2 = MBI_YZX(j[2]);
  // a x b = (a * b.yzx - a.yzx * b).yzx; the last shuffle is linear, so it is applied once.
  __m128 o = _mm_mul_ps(n0, _mm_fmsub_ps(j[1], y2, _mm_mul_ps(y1, j[2])));
  o = _mm_fmadd_ps(n1, _mm_fmsub_ps(j[2], y0, _mm_mul_ps(y2, j[0])), o);
  o = _mm_fmadd_ps(n2, _mm_fmsub_ps(j[0], y1, _mm_mul_ps(y0, j[1])), o);
  o = _mm_blend_ps(MBI_YZX(o), _mm_setzero_ps(), 0x8);  // lane 3 (not a coordinate) to 0
  const __m128 sq = _mm_mul_ps(o, o);
  __m128 s = _mm_add_ps(sq, _mm_shuffle_ps(sq, sq, _MM_SHUFFLE(2, 3, 0, 1)));
  s = _mm_add_ps(s, _mm_shuffle_ps(s, s, _MM_SHUFFLE(1, 0, 3, 2)));
  // 1/sqrt(s): the estimate and one Newton step (relative error about 1e-7)
  __m128 inv = _mm_rsqrt_ps(s);
  const __m128 half_s = _mm_mul_ps(_mm_set1_ps(0.5f), s);
  inv = _mm_mul_ps(inv, _mm_fnmadd_ps(_mm_mul_ps(half_s, inv), inv, _mm_set1_ps(1.5f)));
  const __m128 ok = _mm_cmpgt_ps(s, _mm_set1_ps(1.17549435e-38f));  // 0 where J is singular
  return _mm_and_ps(_mm_mul_ps(o, inv), ok);
}

// 4 results (x, y, z, *) to 3 vectors x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3.
MBI_TARGET inline void pack4(__m128 r0, __m128 r1, __m128 r2, __m128 r3, __m128& o0, __m128& o1,
                             __m128& o2) {
  o0 = _mm_blend_ps(r0, _mm_shuffle_ps(r1, r1, _MM_SHUFFLE(0, 0, 0, 0)), 0x8);
  o1 = _mm_shuffle_ps(r1, r2, _MM_SHUFFLE(1, 0, 2, 1));
  o2 = _mm_blend_ps(_mm_shuffle_ps(r3, r3, _MM_SHUFFLE(2, 1, 0, 0)),
                    _mm_shuffle_ps(r2, r2, _MM_SHUFFLE(2, 2, 2, 2)), 0x1);
}

template <bool Normals>
MBI_TARGET void eval_x86(const std::int32_t* rec, const float* coef, const float* jac,
                         const float* nrest, float* pos, float* nout, long long begin, long long end) {
  constexpr int NC = coef_stride(3), NJ = jac_stride(3);
  const bool aligned = (reinterpret_cast<std::uintptr_t>(pos + 3 * begin) % 16 == 0) &&
                       (!Normals || reinterpret_cast<std::uintptr_t>(nout + 3 * begin) % 16 == 0);
  long long p = begin;
  for (; p + 4 <= end; p += 4) {
    __m128 r[4], q[4];
    for (int k = 0; k < 4; ++k) {
      const __m128i w = _mm_loadu_si128(reinterpret_cast<const __m128i*>(rec + 4 * (p + k)));
      const long long e = _mm_cvtsi128_si32(w);
      const __m128 v = _mm_castsi128_ps(w);
      const __m128 b1 = _mm_shuffle_ps(v, v, 0x55), b2 = _mm_shuffle_ps(v, v, 0xAA),
                   b3 = _mm_shuffle_ps(v, v, 0xFF);
      r[k] = position3(coef + e * NC, b1, b2, b3);
      if constexpr (Normals) q[k] = normal3(jac + e * NJ, b1, b2, b3, nrest + 3 * (p + k));
    }
    __m128 o0, o1, o2;
    pack4(r[0], r[1], r[2], r[3], o0, o1, o2);
    float* out = pos + 3 * p;
    if (aligned) {
      _mm_stream_ps(out, o0);
      _mm_stream_ps(out + 4, o1);
      _mm_stream_ps(out + 8, o2);
    } else {
      _mm_storeu_ps(out, o0);
      _mm_storeu_ps(out + 4, o1);
      _mm_storeu_ps(out + 8, o2);
    }
    if constexpr (Normals) {
      pack4(q[0], q[1], q[2], q[3], o0, o1, o2);
      float* nn = nout + 3 * p;
      if (aligned) {
        _mm_stream_ps(nn, o0);
        _mm_stream_ps(nn + 4, o1);
        _mm_stream_ps(nn + 8, o2);
      } else {
        _mm_storeu_ps(nn, o0);
        _mm_storeu_ps(nn + 4, o1);
        _mm_storeu_ps(nn + 8, o2);
      }
    }
  }
  _mm_sfence();
  for (; p < end; ++p) {  // the last 1-3 points of the range: exact-size stores
    const __m128i w = _mm_loadu_si128(reinterpret_cast<const __m128i*>(rec + 4 * p));
    const long long e = _mm_cvtsi128_si32(w);
    const __m128 v = _mm_castsi128_ps(w);
    const __m128 b1 = _mm_shuffle_ps(v, v, 0x55), b2 = _mm_shuffle_ps(v, v, 0xAA),
                 b3 = _mm_shuffle_ps(v, v, 0xFF);
    alignas(16) float t[4];
    _mm_store_ps(t, position3(coef + e * NC, b1, b2, b3));
    std::memcpy(pos + 3 * p, t, 3 * sizeof(float));
    if constexpr (Normals) {
      _mm_store_ps(t, normal3(jac + e * NJ, b1, b2, b3, nrest + 3 * p));
      std::memcpy(nout + 3 * p, t, 3 * sizeof(float));
    }
  }
}

#endif

}  // namespace

FastEvaluator::FastEvaluator(const Embedding& emb, int threads) : threads_(threads) {
  d_ = emb.dim();
  if (d_ != 2 && d_ != 3)
    throw Error("FastEvaluator: the embedding must be 2D or 3D (bary with 3 or 4 columns), got " +
                std::to_string(emb.bary.cols()) + " columns");
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
              static_cast<float>(emb.gradients(static_cast<Eigen::Index>(e) * (d + 1) + k, r));
  }
  // records: one aligned block (the x86 kernel loads a 3D record as one 16-byte vector)
  records_.assign(static_cast<size_t>(p_) * (d + 1), 0);
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
  normals_.assign(static_cast<size_t>(p_) * d_ + 4, 0.0f);  // padding: 16-byte loads of the last one
  for (long long i = 0; i < p_; ++i)
    for (int c = 0; c < d_; ++c) normals_[static_cast<size_t>(i) * d_ + c] = static_cast<float>(normals(i, c));
}

int FastEvaluator::threads() const {
#ifdef _OPENMP
  int t = threads_ > 0 ? threads_ : omp_get_max_threads();
#else
  const int t = 1;
#endif
  // at least 32K points a thread: below that the fork/join costs more than it saves
  const long long cap = std::max<long long>(1, p_ / 32768);
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
  const int NC = coef_stride(d), NJ = jac_stride(d);
  coef_.resize(static_cast<size_t>(m_) * NC + 16);  // zeros: the padding stays 0
  if (normals) jac_.resize(static_cast<size_t>(m_) * NJ + 16);
  float* const coef = align64(coef_.data());
  float* const jac = normals ? align64(jac_.data()) : nullptr;
  const auto& edges = bezier_edges(d);
  // local edge index of pair (i, j)
  int edge_of[4][4] = {};
  for (size_t s = 0; s < edges.size(); ++s) {
    edge_of[edges[s].first][edges[s].second] = static_cast<int>(s);
    edge_of[edges[s].second][edges[s].first] = static_cast<int>(s);
  }
  const int m = m_;
  MBI_OMP("omp parallel for schedule(static) num_threads(threads()) if (m > 4096)")
  for (int e = 0; e < m; ++e) {
    auto P = [&](int k, int c) { return B(static_cast<Eigen::Index>(e) * K + k, c); };
    auto Pe = [&](int i, int j, int c) { return P(d + 1 + edge_of[i][j], c); };
    double cl[4][3] = {}, cq[4][4][3] = {};  // c_k, c_kl (symmetric)
    float* C = coef + static_cast<size_t>(e) * NC;
    for (int c = 0; c < d; ++c) C[c] = static_cast<float>(P(0, c));
    for (int k = 1; k <= d; ++k)
      for (int c = 0; c < d; ++c) {
        cl[k][c] = 2 * (Pe(0, k, c) - P(0, c));
        cq[k][k][c] = P(0, c) + P(k, c) - 2 * Pe(0, k, c);
        for (int l = k + 1; l <= d; ++l)
          cq[k][l][c] = cq[l][k][c] = 2 * (P(0, c) - Pe(0, k, c) - Pe(0, l, c) + Pe(k, l, c));
      }
    int s = 1;
    for (int k = 1; k <= d; ++k) {
      for (int c = 0; c < d; ++c) C[s * d + c] = static_cast<float>(cl[k][c]);
      ++s;
      for (int l = k; l <= d; ++l, ++s)
        for (int c = 0; c < d; ++c) C[s * d + c] = static_cast<float>(cq[k][l][c]);
    }
    if (!normals) continue;
    float* G = jac + static_cast<size_t>(e) * NJ;
    const float* a = grads_.data() + static_cast<size_t>(e) * d * d;  // a[(k-1) d + r]
    for (int r = 0; r < d; ++r) {
      float* g = G + r * (d + 1) * d;
      for (int c = 0; c < d; ++c) {
        double j0 = 0;
        for (int k = 1; k <= d; ++k) j0 += a[(k - 1) * d + r] * cl[k][c];
        g[c] = static_cast<float>(j0);
        for (int l = 1; l <= d; ++l) {
          double v = 0;
          for (int k = 1; k <= d; ++k) v += a[(k - 1) * d + r] * (k == l ? 2.0 : 1.0) * cq[k][l][c];
          g[l * d + c] = static_cast<float>(v);
        }
      }
    }
  }
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
  const float* jac = with_normals ? align64(jac_.data()) : nullptr;
  const float* nrest = with_normals ? normals_.data() : nullptr;
  const int d = d_;
  const long long p = p_;
  auto run = [&](long long begin, long long end) {
#ifdef MBI_FAST_X86
    if (d == 3 && detail::have_avx2_fma()) {
      if (with_normals) eval_x86<true>(rec, coef, jac, nrest, positions, normals, begin, end);
      else eval_x86<false>(rec, coef, jac, nrest, positions, normals, begin, end);
      return;
    }
#endif
    if (d == 3) eval_scalar<3>(rec, coef, jac, nrest, positions, normals, begin, end);
    else eval_scalar<2>(rec, coef, jac, nrest, positions, normals, begin, end);
  };
  const int nt = threads();
  if (nt <= 1) {
    run(0, p);
    return;
  }
#ifdef _OPENMP
#pragma omp parallel num_threads(nt)
  {
    long long begin, end;
    chunk(p, omp_get_thread_num(), omp_get_num_threads(), begin, end);
    run(begin, end);
  }
#endif
}

}  // namespace mbi::interp
