// FastEvaluator (see fast_evaluate.hpp): packs the records and rest normals, writes each call's
// element terms, and runs the kernel of its instruction set (fast_kernel.hpp) over the points;
// or, records in element order without normals, computes the terms of a block of elements at a
// time and runs the kernel on those elements' records at once (the fused pass). The terms are
// computed in double from B and rounded to float once per call, by the same function either way.
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

// The terms of elements [e0, e1) from their Bezier points B ((m K) x D, K = (D+1)(D+2)/2, the
// vertices then the edges in the order of bezier_edges(D)), computed in double and rounded to
// float once, written in layout L at C (element e's coef_stride(D) floats at C + (e - e0)
// coef_stride(D)); the floats no term uses are set to 0 (a call may change the layout; the
// kernels read them but ignore what they give). Returns the largest |c_k| (the scale of the
// derivatives dx/db_k). Everything below is known at compile time but B: no scratch to clear, no
// offset table to read per element. Each element prefetches the Bezier points kBAhead elements
// on: a fused pass computes the terms in short bursts between kernel runs, and the hardware
// prefetcher starts each burst's three column streams anew.
constexpr long long kBAhead = 16;

// The byte at p + bytes, prefetched: integer arithmetic, so that an address past the end of B is
// never formed as a pointer (a prefetch does not fault).
void prefetch_at(const void* p, long long bytes) {
  __builtin_prefetch(reinterpret_cast<const char*>(reinterpret_cast<std::uintptr_t>(p) + static_cast<std::uintptr_t>(bytes)));
}

template <int D, const Layout& L>
double terms_of(const MatrixIn& B, float* C0, long long e0, long long e1) {
  constexpr int K = (D + 1) * (D + 2) / 2, NC = coef_stride(D);
  static constexpr TermIndex ix(D);
  static constexpr auto unused = [] {  // the floats no term uses
    std::array<bool, NC> free{};
    for (bool& f : free) f = true;
    for (int c = 0; c < D; ++c) {
      free[L.at(0, c)] = false;
      for (int k = 1; k <= D; ++k) {
        free[L.at(ix.lin[k], c)] = false;
        for (int l = k; l <= D; ++l) free[L.at(ix.quad[k][l], c)] = false;
      }
    }
    std::array<int, NC - D * detail::position_terms(D)> list{};
    for (int f = 0, n = 0; f < NC; ++f)
      if (free[f]) list[n++] = f;
    return list;
  }();
  // row of the Bezier point on edge (i, j) within an element's K rows
  int edge_row[D + 1][D + 1] = {};
  const auto& edges = bezier_edges(D);
  for (size_t s = 0; s < edges.size(); ++s)
    edge_row[edges[s].first][edges[s].second] = edge_row[edges[s].second][edges[s].first] =
        D + 1 + static_cast<int>(s);
  const std::ptrdiff_t is = B.innerStride();  // rows is doubles apart (1 in a BezierPoints)
  double dmax = 0;
  for (long long e = e0; e < e1; ++e) {
    float* C = C0 + static_cast<size_t>(e - e0) * NC;
    for (int f : unused) C[f] = 0.0f;
    for (int c = 0; c < D; ++c) {  // an element's K doubles of a column: 2 lines at most (is = 1)
      const double* P = B.data() + c * B.outerStride() + e * K * is;
      prefetch_at(P, kBAhead * K * is * 8);
      prefetch_at(P, kBAhead * K * is * 8 + 64);
    }
    for (int c = 0; c < D; ++c) {
      const double* P = B.data() + c * B.outerStride() + e * K * is;
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
  return dmax;
}

// The terms of elements [0, m) (terms_of) at coef, in blocks of elements on up to `threads`
// threads (more than 512 elements); returns the largest |c_k|.
template <int D, const Layout& L>
double prepare_terms(const MatrixIn& B, float* coef, int m, int threads) {
  std::atomic<double> dmax_all{0.0};
  detail::parallel_blocks(m, 256, m > 512 ? threads : 1, [&](long long e0, long long e1) {
    const double dmax = terms_of<D, L>(B, coef + static_cast<size_t>(e0) * coef_stride(D), e0, e1);
    for (double cur = dmax_all.load(); dmax > cur && !dmax_all.compare_exchange_weak(cur, dmax);) {
    }
  });
  return dmax_all.load();
}

// Elements whose terms a fused pass computes at a time (evaluate_fused()): their 128 KiB (3D)
// stay in L2 until the records that read them are done. Smaller blocks, in L1, ran slower: each
// switch between the two streams (Bezier points, then records) costs more than L1 saves.
constexpr int kFuseElements = 1024;

// The end of the records from p (< mid, in element order: rec, d + 1 words a record) whose
// elements span fewer than kFuseElements: the most whole groups before mid (a binary search),
// p when the first group spans more (points sparser than elements).
long long fused_end(const std::int32_t* rec, int d, long long p, long long mid, long long group) {
  auto element = [&](long long k) { return static_cast<long long>(rec[k * (d + 1)]); };
  const long long e_end = element(p) + kFuseElements;
  long long lo = 0, hi = (mid - p) / group;  // groups known to fit, groups at most
  while (lo < hi) {
    const long long j = (lo + hi + 1) / 2;
    if (element(p + j * group - 1) < e_end) lo = j;
    else hi = j - 1;
  }
  return p + lo * group;
}

// What a fused pass reads and writes: records in element order (their own, or sorted with a
// permutation: row), its ranges of records (FastEvaluator::plan_fused()), the terms' function
// and the kernels of the call.
struct FusedPass {
  const MatrixIn& B;
  const std::int32_t* rec;
  const std::int32_t* row;  // the output row of each record, or nullptr: record k's is row k
  const long long* ends;    // the ranges' ends, block after block of kBlock records
  const std::size_t* first; // block i's ranges: ends[first[i]] .. ends[first[i + 1] - 1]
  float* pos;
  int d;
  const Layout& L;
  double (*terms)(const MatrixIn&, float*, long long, long long);
  detail::Kernel x86, x86_in_order;  // positions without prefetches (nullptr: the portable loop)
  long long group;                   // 4 with the x86 kernels, 1 with the portable loop

  std::int32_t element(long long k) const { return rec[k * (d + 1)]; }
  long long out_row(long long k) const { return row ? row[k] : k; }
};

// Records [p, q) (whole groups): their elements' terms into buf, then the kernel on them.
void fused_range(const FusedPass& f, float* buf, long long p, long long q) {
  const std::int32_t e0 = f.element(p);
  f.terms(f.B, buf, e0, static_cast<long long>(f.element(q - 1)) + 1);
  if (f.x86) f.x86(f.rec, buf, e0, nullptr, 1.0f, f.pos, nullptr, f.row, p, q);
  else detail::eval_portable(f.d, f.rec, buf, e0, f.L, nullptr, 1.0f, f.pos, nullptr, f.row, p, q);
}

// Records [a, b) (at most a group: a block's last records, or a group whose elements span more
// than buf holds) as a whole group of copies whose element ids count the group's elements
// (terms computed in that order): the same arithmetic as in any other group, nothing read
// outside buf. The results go through scratch to the records' rows (off 16-byte alignment:
// plain stores, read back at once).
void fused_group(const FusedPass& f, float* buf, long long a, long long b) {
  constexpr int NR = 4;  // words a 3D record (the x86 kernels are 3D)
  alignas(16) std::int32_t local[4 * NR];
  std::int32_t slot = -1, prev = -1;
  for (long long k = a; k < a + 4; ++k) {
    const long long src = std::min(k, b - 1);  // the last record again after b
    if (const std::int32_t e = f.element(src); e != prev) {
      f.terms(f.B, buf + ++slot * coef_stride(3), e, e + 1LL);
      prev = e;
    }
    std::copy(f.rec + src * NR, f.rec + src * NR + NR, local + (k - a) * NR);
    local[(k - a) * NR] = slot;
  }
  alignas(16) float tp[13];
  f.x86_in_order(local, buf, 0, nullptr, 1.0f, tp + 1, nullptr, nullptr, 0, 4);
  for (long long k = a; k < b; ++k) std::copy(tp + 1 + 3 * (k - a), tp + 4 + 3 * (k - a), f.pos + 3 * f.out_row(k));
}

// Records [begin, end) of a fused pass (whole blocks of kBlock records): range after range, each
// one's terms computed into a buffer of this thread and read back at once by the kernel.
void fused_blocks(const FusedPass& f, long long begin, long long end) {
  // the terms' buffer: scratch of this thread, kept between calls (64-byte aligned)
  thread_local std::vector<float> scratch;
  scratch.resize(std::max(scratch.size(), static_cast<size_t>(kFuseElements) * coef_stride(3) + 16));
  float* const buf = align64(scratch.data());
  for (long long b = begin; b < end; b += kBlock) {
    const auto i = static_cast<size_t>(b / kBlock);
    long long p = b;
    for (size_t r = f.first[i]; r < f.first[i + 1]; p = f.ends[r++]) {
      const long long q = f.ends[r];
      if (q - p == f.group && f.element(q - 1) - f.element(p) >= kFuseElements) fused_group(f, buf, p, q);
      else fused_range(f, buf, p, q);
    }
    if (const long long block_end = std::min(b + kBlock, end); p < block_end) fused_group(f, buf, p, block_end);
  }
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
  long long same = 0, ordered = 1;
  for (long long k = 1; k < p_; ++k) {
    same += records_[k * (d + 1)] == records_[(k - 1) * (d + 1)];
    ordered += records_[k * (d + 1)] >= records_[(k - 1) * (d + 1)];
  }
  coherent_ = 2 * same >= p_;
  ordered_ = ordered >= p_;
  if (ordered_) plan_fused();
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

void FastEvaluator::check(const MatrixIn& B, bool normals) const {
  const int d = d_;
  const int K = (d + 1) * (d + 2) / 2;
  if (B.cols() != d || B.rows() % K != 0 || B.rows() / K < m_)
    throw Error("Bezier points must be (m " + std::to_string(K) + ") x " +
                std::to_string(d) + " with m >= " + std::to_string(m_) + ", got " +
                std::to_string(B.rows()) + " x " + std::to_string(B.cols()));
  if (normals && !has_rest_normals()) throw Error("normals asked for, but no rest normals were set");
}

void FastEvaluator::prepare(const MatrixIn& B, bool normals) {
  check(B, normals);
  const int d = d_;
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
  if (!with_normals && fused_terms()) return evaluate_fused(B, positions);
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
    if (!x86) return detail::eval_portable(d, rec, coef, 0, L, mrest, sigma, positions, normals, row, begin, end);
    const long long mid = begin + (end - begin) / group * group;
    x86(rec, coef, 0, mrest, sigma, positions, normals, row, begin, mid);
    if (mid == end) return;
    // The last records: a whole group (the padding records after them) into scratch, then their
    // rows copied: the same arithmetic as every other point, wherever it lies. The scratch is off
    // 16-byte alignment: plain stores, as it is read back at once.
    alignas(16) float tp[49], tn[49];
    x86_in_order(rec + (d + 1) * mid, coef, 0, mrest ? mrest + d * mid : nullptr, sigma, tp + 1, normals ? tn + 1 : nullptr,
                 nullptr, 0, group);
    for (long long k = mid; k < end; ++k) {
      const long long r = d * static_cast<long long>(point(k)), s = 1 + d * (k - mid);
      std::copy(tp + s, tp + s + d, positions + r);
      if (normals) std::copy(tn + s, tn + s + d, normals + r);
    }
  });
}

// Positions with the element terms computed block by block alongside the records (fused_blocks()):
// each thread takes whole blocks of records, and an element whose records straddle two blocks is
// computed by both. No sigma: positions do not scale by it.
void FastEvaluator::evaluate_fused(const MatrixIn& B, float* positions) {
  check(B, false);
  const int d = d_;
  const Layout& L = layout_for(d, false, simd_);
  detail::Kernel x86 = nullptr, x86_in_order = nullptr;
#ifdef MBI_INTERP_X86
  if (simd_ == Simd::Avx512 || simd_ == Simd::Avx2) {
    // the terms were just written, in cache: the kernels without prefetches
    const auto& variant = (simd_ == Simd::Avx512 ? detail::avx512_kernels : detail::avx2_kernels)[0][0];
    x86 = variant[order_.empty() ? 0 : 1];
    x86_in_order = variant[0];
  }
#endif
  const FusedPass f{B, records_.data(), order_.empty() ? nullptr : order_.data(), fuse_ends_.data(),
                    fuse_first_.data(), positions, d, L, d == 2 ? &terms_of<2, kPacked2> : &terms_of<3, kPairs>,
                    x86, x86_in_order, fuse_group()};
  detail::parallel_blocks(p_, kBlock, threads(), [&](long long begin, long long end) { fused_blocks(f, begin, end); });
}

// The fused pass's ranges of records, once (the records keep their order): in each block of
// kBlock records, whole groups whose elements span fewer than kFuseElements, or one group that
// spans more (run alone: fused_group()); the block's last records short of a group in none.
void FastEvaluator::plan_fused() {
  const long long group = fuse_group();
  fuse_ends_.clear();
  fuse_first_.clear();
  for (long long b = 0; b < p_; b += kBlock) {
    fuse_first_.push_back(fuse_ends_.size());
    const long long end = std::min(b + kBlock, p_), mid = b + (end - b) / group * group;
    for (long long p = b; p < mid; p = fuse_ends_.back())
      fuse_ends_.push_back(std::max(fused_end(records_.data(), d_, p, mid, group), p + group));
  }
  fuse_first_.push_back(fuse_ends_.size());
}

}  // namespace mbi::interp
