// FastEvaluator (see fast_evaluate.hpp): packs the records and rest normals, writes each call's
// element terms, and runs the kernel of its instruction set (fast_kernel.hpp) over the points.
// The terms are computed in double from B and rounded to float once per call.
#include <mbi/interp/fast_evaluate.hpp>
#include <mbi/interp/threads.hpp>

#include "evaluate/fast_kernel.hpp"
#include "runtime/threads.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <string>

namespace mbi::interp {
namespace {

using detail::coef_stride;
using detail::kPacked2;
using detail::kPacked3;
using detail::kPairs;
using detail::kPrefetch;
using detail::kRowAhead;
using detail::Layout;
using detail::TermIndex;

// Points a thread takes at a time (a multiple of 16); also the fewest points a thread is given.
constexpr long long kBlock = 32768;
static_assert(kBlock % 4 == 0, "blocks must keep each thread's first output float 16-byte aligned");
static_assert(kBlock % 16 == 0, "the AVX-512 kernel's 16-point groups of rest normals (set_rest_normals) "
                                "must start at each block's first point");

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

// Element terms above this many bytes are read from memory, not a cache, by points in random
// order: 2 lines a point. Sorted by element, the terms stream in once and each result is a
// scattered 12-byte store instead (10M points, 511K tetrahedra: 85 -> 64 ms a frame). Below it
// the terms come from L2 or L3 and the scatter costs more than it saves (1M points, 1,764
// tetrahedra: 1.2 -> 1.9 ms; 10M points, 6,000 tetrahedra: 14 -> 53 ms).
constexpr double kSortAbove = 16.0 * 1024 * 1024;

// The points in a stable order by element (order[k]: the point of record k, then kRowAhead
// entries of row 0), or nothing when their own order serves as well: sorted already, mostly
// following a point of the same element (a mesh's order), or terms that fit a cache.
std::vector<std::int32_t> element_order(const Eigen::VectorXi& element, int m, int d) {
  const Eigen::Index p = element.size();
  Eigen::Index same = 0, sorted = 1;
  for (Eigen::Index i = 1; i < p; ++i) {
    same += element(i) == element(i - 1);
    sorted += element(i) >= element(i - 1);
  }
  if (sorted >= p || 2 * same >= p || static_cast<double>(m) * coef_stride(d) * sizeof(float) <= kSortAbove) return {};
  std::vector<std::int32_t> first(static_cast<size_t>(m) + 1, 0);  // counts, then each element's first record
  for (Eigen::Index i = 0; i < p; ++i) ++first[static_cast<size_t>(element(i)) + 1];
  for (size_t e = 1; e < first.size(); ++e) first[e] += first[e - 1];
  std::vector<std::int32_t> order(static_cast<size_t>(p) + kRowAhead, 0);
  for (Eigen::Index i = 0; i < p; ++i)
    order[static_cast<size_t>(first[static_cast<size_t>(element(i))]++)] = static_cast<std::int32_t>(i);
  return order;
}

std::int32_t as_word(float f) {
  std::int32_t w;
  std::memcpy(&w, &f, sizeof w);
  return w;
}

// The terms of elements [0, m) from their Bezier points B ((m K) x D, K = (D+1)(D+2)/2, the
// vertices then the edges in the order of bezier_edges(D)), computed in double and rounded to
// float once, written in layout L; the floats no term uses are set to 0 (a call may change the
// layout; the kernels read them but ignore what they give). Returns the largest |c_k| (the
// scale of the derivatives dx/db_k). Everything below is known at compile time but B: no scratch
// to clear, no offset table to read per element.
template <int D, const Layout& L>
double prepare_terms(const MatrixIn& B, float* coef, int m, int threads) {
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
  for (int c = 0; c < D; ++c) col[c] = B.data() + c * B.outerStride();
  const std::ptrdiff_t is = B.innerStride();  // rows is doubles apart (1 in a BezierPoints)
  // blocks of elements on up to `threads` threads (more than 512 elements); the largest |c_k|
  // of each block joins the maximum
  std::atomic<double> dmax_all{0.0};
  detail::parallel_blocks(m, 256, m > 512 ? threads : 1, [&](long long e0, long long e1) {
    double dmax = 0;
    for (long long e = e0; e < e1; ++e) {
      const long long row = e * K;
      float* C = coef + static_cast<size_t>(e) * NC;
      for (int f = 0; f < NC; ++f)
        if (unused[f]) C[f] = 0.0f;
      for (int c = 0; c < D; ++c) {
        const double* P = col[c] + row * is;
        auto Pe = [&](int i, int j) { return P[edge_row[i][j] * is]; };
        C[L.at(0, c)] = static_cast<float>(P[0]);
        for (int k = 1; k <= D; ++k) {
          const double ck = 2 * (Pe(0, k) - P[0]);
          dmax = std::max(dmax, std::abs(ck));
          C[L.at(ix.lin[k], c)] = static_cast<float>(ck);
          C[L.at(ix.quad[k][k], c)] = static_cast<float>(P[0] + P[k * is] - 2 * Pe(0, k));
          for (int l = k + 1; l <= D; ++l)
            C[L.at(ix.quad[k][l], c)] = static_cast<float>(2 * (P[0] - Pe(0, k) - Pe(0, l) + Pe(k, l)));
        }
      }
    }
    for (double cur = dmax_all.load(); dmax > cur && !dmax_all.compare_exchange_weak(cur, dmax);) {
    }
  });
  return dmax_all.load();
}

}  // namespace

namespace detail {
double pairs_terms3(const MatrixIn& B, float* coef, int m, int threads) {
  return prepare_terms<3, kPairs>(B, coef, m, threads);
}
}  // namespace detail

bool FastEvaluator::supported(Simd s) {
#ifdef MBI_INTERP_X86
  if (s == Simd::Avx512) return detail::have_avx512();
  if (s == Simd::Avx2) return detail::have_avx2_fma();
#else
  if (s == Simd::Avx512 || s == Simd::Avx2) return false;
#endif
  return true;
}

const char* FastEvaluator::name(Simd s) { return kSimdNames.name(s); }

FastEvaluator::FastEvaluator(const Embedding& emb, int threads, Simd simd) : threads_(threads) {
  d_ = emb.dim();
  if (d_ != 2 && d_ != 3)
    throw Error("the embedding must be 2D or 3D (bary with 3 or 4 columns), got " +
                std::to_string(emb.bary.cols()) + " columns");
  if (simd != Simd::Auto && !supported(simd))
    throw Error(std::string("this CPU cannot run the ") + name(simd) + " kernels");
  if (simd == Simd::Auto) simd = supported(Simd::Avx512) ? Simd::Avx512 : supported(Simd::Avx2) ? Simd::Avx2 : Simd::Portable;
  simd_ = d_ == 3 ? simd : Simd::Portable;
  if (emb.bary.rows() != emb.element.size())
    throw Error("embedding has " + std::to_string(emb.element.size()) + " elements but " +
                std::to_string(emb.bary.rows()) + " coordinate rows");
  check_threads(threads);
  p_ = emb.size();
  const int d = d_;
  m_ = 0;
  for (long long i = 0; i < p_; ++i) {
    if (emb.element(i) < 0)
      throw Error("point " + std::to_string(i) + " refers to element " +
                  std::to_string(emb.element(i)));
    m_ = std::max(m_, emb.element(i) + 1);
  }
  if (emb.gradients.rows() > 0) {
    if (emb.gradients.cols() != d || emb.gradients.rows() % (d + 1) != 0 ||
        emb.gradients.rows() / (d + 1) < m_)
      throw Error("the embedding's basis gradients are " +
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
  // records, in element order where that pays (element_order()): one block (the x86 kernel
  // loads two 3D records as one 32-byte vector), then kPrefetch + 16 records of element 0 for
  // the prefetches past the end and the last group (evaluate())
  order_ = element_order(emb.element, m_, d);
  records_.assign(static_cast<size_t>(p_ + kPrefetch + 16) * (d + 1), 0);
  for (long long k = 0; k < p_; ++k) {
    const Eigen::Index i = point(k);
    std::int32_t* r = records_.data() + k * (d + 1);
    r[0] = emb.element(i);
    for (int c = 1; c <= d; ++c) r[c] = as_word(static_cast<float>(emb.bary(i, c)));
  }
  // Records stored coherently (a mesh's vertices, or sorted: most follow a record of the same
  // element) find their element's terms in L1 already; the prefetches only help the others.
  long long same = 0;
  for (long long k = 1; k < p_; ++k) same += records_[k * (d + 1)] == records_[(k - 1) * (d + 1)];
  coherent_ = 2 * same >= p_;
}

void FastEvaluator::set_rest_normals(const Eigen::Ref<const Eigen::MatrixXd>& normals) {
  if (normals.rows() != p_ || normals.cols() != d_)
    throw Error("rest normals must be " + std::to_string(p_) + " x " + std::to_string(d_) +
                ", got " + std::to_string(normals.rows()) + " x " + std::to_string(normals.cols()));
  if (grads_.empty() && p_ > 0)
    throw Error("normals need the embedding's basis gradients (filled by embed())");
  // m = cof(A)^T n per point, A = [a_1 .. a_d] (the element's basis gradients as columns):
  // m_k = n . (column k of cof(A)); in 3D column k is a_{k+1} x a_{k+2}.
  // padding: the last group of 4 (up to 16 floats from its first record), and room to move the
  // block (rest_normals_for())
  normals_.assign(static_cast<size_t>(p_) * d_ + kPad + kSlack, 0.0f);  // one per record
  moff_ = 0;
  moves_ = 0;
  const int d = d_;
  for (long long q = 0; q < p_; ++q) {
    const double* a = grads_.data() + static_cast<size_t>(records_[static_cast<size_t>(q) * (d + 1)]) * d * d;
    auto g = [&](int k, int r) { return a[(k - 1) * d + r]; };  // component r of a_k
    const Eigen::Index i = point(q);
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
      normals_[static_cast<size_t>(q) * d + c] = static_cast<float>(std::ldexp(m[c], -ex));
  }
  // The AVX-512 kernel takes each whole group of 16 points (groups start at multiples of 16:
  // every thread's block does) as three registers, one component each, lane 4 g + k holding
  // point 4 k + g (Normals16): stored in that order, it loads them without a permute. The last,
  // partial group too, padded with zeros: evaluate() runs it as a whole group.
  if (simd_ == Simd::Avx512 && d == 3) {
    float g[48];
    for (long long q = 0; q < p_; q += 16) {
      float* block = normals_.data() + 3 * q;
      for (int c = 0; c < 3; ++c)
        for (int l = 0; l < 16; ++l) g[16 * c + l] = block[3 * (4 * (l % 4) + l / 4) + c];
      std::copy(g, g + 48, block);
    }
  }
}

int FastEvaluator::threads() const {
  // at least kBlock points a thread: below that sharing costs more than it saves
  return detail::thread_count(p_, kBlock, threads_);
}

void FastEvaluator::prepare(const MatrixIn& B, bool normals) {
  const int d = d_;
  const int K = (d + 1) * (d + 2) / 2;
  if (B.cols() != d || B.rows() % K != 0 || B.rows() / K < m_)
    throw Error("Bezier points must be (m " + std::to_string(K) + ") x " +
                std::to_string(d) + " with m >= " + std::to_string(m_) + ", got " +
                std::to_string(B.rows()) + " x " + std::to_string(B.cols()));
  if (normals && !has_rest_normals()) throw Error("normals asked for, but no rest normals were set");
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
// low 12 address bits and waits on it ("4K aliasing", a large share of the whole pass). So
// (block - output) modulo 4 KiB is kept within [lo, 3072] bytes for both outputs: stores up to 1024 bytes behind the loads are clear of them (the AVX2
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
    std::memmove(normals_.data() + off, normals_.data() + moff_, (static_cast<size_t>(p_) * d_ + kPad) * sizeof(float));
    moff_ = off;
  }
  return normals_.data() + moff_;
}

void FastEvaluator::evaluate(const MatrixIn& B, RowMatrixXf& positions) {
  if (positions.rows() != p_ || positions.cols() != d_) positions.resize(p_, d_);
  evaluate(B, positions.data(), nullptr);
}

void FastEvaluator::evaluate(const MatrixIn& B, RowMatrixXf& positions, RowMatrixXf& normals) {
  if (positions.rows() != p_ || positions.cols() != d_) positions.resize(p_, d_);
  if (normals.rows() != p_ || normals.cols() != d_) normals.resize(p_, d_);
  evaluate(B, positions.data(), normals.data());
}

void FastEvaluator::evaluate(const MatrixIn& B, float* positions, float* normals) {
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
  detail::Kernel x86 = nullptr, x86_in_order = nullptr;
#ifdef MBI_INTERP_X86
  if (simd_ == Simd::Avx512 || simd_ == Simd::Avx2) {
    const detail::KernelTable& kernels = simd_ == Simd::Avx512 ? detail::avx512_kernels : detail::avx2_kernels;
    // sigma within 2^+-16 leaves |cof(D) m|^2 within 2^+-64 (m: [0.5, 1)): no scaling needed
    const bool scaled = !(sigma >= 0x1p-16f && sigma <= 0x1p16f);
    const auto& variant = kernels[with_normals ? (scaled ? 2 : 1) : 0][coherent_ ? 0 : 1];
    x86 = variant[order_.empty() ? 0 : 1];
    x86_in_order = variant[0];
  }
#endif
  const std::int32_t* row = order_.empty() ? nullptr : order_.data();
  // the x86 kernels' groups: 4 points, 16 for the AVX-512 normals (groups of 4 there sum in
  // another order)
  const long long group = simd_ == Simd::Avx512 && with_normals ? 16 : 4;
  // kBlock points a block, a multiple of 16 (each block's first output float stays 16-byte aligned)
  detail::parallel_blocks(p, kBlock, threads(), [&](long long begin, long long end) {
    if (!x86) return detail::eval_portable(d, rec, coef, L, mrest, sigma, positions, normals, row, begin, end);
    const long long mid = begin + (end - begin) / group * group;
    x86(rec, coef, mrest, sigma, positions, normals, row, begin, mid);
    if (mid == end) return;
    // The last records: a whole group (the padding records after them) into scratch, then their
    // rows copied: the same arithmetic as every other point, wherever it lies. The scratch is off
    // 16-byte alignment: plain stores, as it is read back at once.
    alignas(16) float tp[49], tn[49];
    x86_in_order(rec + (d + 1) * mid, coef, mrest ? mrest + d * mid : nullptr, sigma, tp + 1, normals ? tn + 1 : nullptr,
                 nullptr, 0, group);
    for (long long k = mid; k < end; ++k) {
      const long long r = d * static_cast<long long>(point(k)), s = 1 + d * (k - mid);
      std::copy(tp + s, tp + s + d, positions + r);
      if (normals) std::copy(tn + s, tn + s + d, normals + r);
    }
  });
}

}  // namespace mbi::interp
