// The memory estimate of a modified-BI run (see mbi/interp/memory.hpp).
#include <mbi/interp/memory.hpp>

#include "linalg/factor.hpp"
#include "method/detail.hpp"

#include <mbi/error.hpp>

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <sstream>
#include <vector>

#ifdef MBI_HAVE_CHOLMOD
#include <cholmod.h>
#endif

namespace mbi::interp {

namespace {

// The vertex graph of the m-block, lower triangle by columns (diagonal included): vertices
// coupled by an element (E_vibr) or by the two elements of an interior face (E_disc), every
// m-block entry of a coupled pair possibly nonzero. Vertices whose M is fixed (`keep` 0) are left
// out and the others numbered in order.
struct VertexGraph {
  int n = 0;
  std::vector<long long> colp;
  std::vector<int> rows;
  long long full_entries() const { return 2 * static_cast<long long>(rows.size()) - n; }
};

VertexGraph vertex_graph(const Eigen::MatrixXi& T, const std::vector<int>& index, int n_kept) {
  const int d1 = static_cast<int>(T.cols()), d = d1 - 1;
  const Eigen::MatrixXi F = interior_faces(T);
  std::vector<std::uint64_t> pairs;
  pairs.reserve(static_cast<size_t>(T.rows()) * d1 * (d1 + 1) / 2 + static_cast<size_t>(F.rows()) * (d + 2) * (d + 3) / 2);
  int group[8];
  auto add = [&](int size) {
    for (int a = 0; a < size; ++a)
      for (int b = 0; b <= a; ++b) {
        const int i = index[group[a]], j = index[group[b]];
        if (i < 0 || j < 0) continue;
        pairs.push_back((static_cast<std::uint64_t>(std::min(i, j)) << 32) | static_cast<std::uint32_t>(std::max(i, j)));
      }
  };
  for (Eigen::Index e = 0; e < T.rows(); ++e) {
    for (int k = 0; k < d1; ++k) group[k] = T(e, k);
    add(d1);
  }
  for (Eigen::Index f = 0; f < F.rows(); ++f) {  // the face's vertices and the two opposite ones
    int size = d;
    for (int k = 0; k < d; ++k) group[k] = F(f, k);
    for (int side : {F(f, d), F(f, d + 1)})
      for (int k = 0; k < d1; ++k) {
        const int v = T(side, k);
        if (std::find(group, group + d, v) == group + d) group[size++] = v;
      }
    add(size);
  }
  // bucketed by column, then each column's few rows sorted: no sort of all the pairs
  VertexGraph G;
  G.n = n_kept;
  std::vector<long long> start(static_cast<size_t>(n_kept) + 1, 0);
  for (std::uint64_t q : pairs) ++start[(q >> 32) + 1];
  for (int j = 0; j < n_kept; ++j) start[j + 1] += start[j];
  std::vector<int> rows(pairs.size());
  {
    std::vector<long long> next(start.begin(), start.end() - 1);
    for (std::uint64_t q : pairs) rows[static_cast<size_t>(next[q >> 32]++)] = static_cast<int>(q & 0xffffffffu);
  }
  pairs = {};
  G.colp.assign(static_cast<size_t>(n_kept) + 1, 0);
  long long out = 0;
  for (int j = 0; j < n_kept; ++j) {
    int* b = rows.data() + start[j];
    int* e = rows.data() + start[j + 1];
    std::sort(b, e);
    e = std::unique(b, e);
    for (int* r = b; r != e; ++r) rows[static_cast<size_t>(out++)] = *r;  // out <= r: moves left
    G.colp[j + 1] = out;
  }
  rows.resize(static_cast<size_t>(out));
  G.rows = std::move(rows);
  return G;
}

// What the symbolic analysis of the m-block gives, from that of its vertex graph: each vertex is
// d unknowns, so a supernode of c columns and r rows becomes one of d c and d r.
struct Symbolic {
  double values = 0, row_indices = 0, update_values = 0, flops = 0;
  std::string ordering;
};

#ifdef MBI_HAVE_CHOLMOD
Symbolic analyse_cholmod(const VertexGraph& G, int d) {
  cholmod_common c;
  cholmod_start(&c);
  c.supernodal = CHOLMOD_SUPERNODAL;
  c.print = 0;
  c.nmethods = static_cast<long long>(d) * G.n < detail::kMetisMinUnknowns ? 1 : 2;
  c.method[0].ordering = CHOLMOD_AMD;
  c.method[1].ordering = CHOLMOD_METIS;
  c.postorder = 1;
  cholmod_sparse* A = cholmod_allocate_sparse(G.n, G.n, G.rows.size(), 1, 1, -1, CHOLMOD_PATTERN, &c);
  cholmod_factor* L = nullptr;
  if (A) {
    int* p = static_cast<int*>(A->p);
    for (int j = 0; j <= G.n; ++j) p[j] = static_cast<int>(G.colp[j]);
    std::copy(G.rows.begin(), G.rows.end(), static_cast<int*>(A->i));
    std::lock_guard<std::mutex> one_at_a_time(detail::ordering_mutex());
    L = cholmod_analyze(A, &c);
  }
  const int status = c.status;
  Symbolic s;
  if (L && status >= CHOLMOD_OK && L->is_super) {
    const double dd = d;
    s.values = dd * dd * static_cast<double>(L->xsize);
    s.row_indices = dd * static_cast<double>(L->ssize);
    s.update_values = dd * dd * static_cast<double>(L->maxcsize);
    s.flops = dd * dd * dd * c.fl;
    s.ordering = L->ordering == CHOLMOD_METIS ? "METIS" : "AMD";
  }
  if (L) cholmod_free_factor(&L, &c);
  if (A) cholmod_free_sparse(&A, &c);
  cholmod_finish(&c);
  if (s.ordering.empty())
    throw Error(status == CHOLMOD_TOO_LARGE
                    ? "memory estimate: the factor of " + std::to_string(G.n) +
                          " control vertices is too large for CHOLMOD's 32-bit indices"
                    : "memory estimate: CHOLMOD's symbolic analysis failed (status " + std::to_string(status) +
                          (status == CHOLMOD_OUT_OF_MEMORY ? ": out of memory)" : ")"));
  return s;
}
#endif

// Without CHOLMOD: Eigen's factor (AMD) of an SPD matrix on the vertex graph gives the counts.
Symbolic analyse_eigen(const VertexGraph& G, int d) {
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(2 * G.rows.size());
  for (int j = 0; j < G.n; ++j)
    for (long long k = G.colp[j]; k < G.colp[j + 1]; ++k) {
      const int i = G.rows[static_cast<size_t>(k)];
      if (i == j) t.emplace_back(i, i, 1.0 + static_cast<double>(G.colp[j + 1] - G.colp[j]) * 64);
      else t.emplace_back(i, j, -1.0), t.emplace_back(j, i, -1.0);
    }
  Eigen::SparseMatrix<double> A(G.n, G.n);
  A.setFromTriplets(t.begin(), t.end());
  t = {};
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> llt(A);
  if (llt.info() != Eigen::Success) throw Error("memory estimate: the vertex graph's factorization failed");
  const Eigen::SparseMatrix<double>& L = llt.matrixL().nestedExpression();
  Symbolic s;
  const double dd = d;
  // Eigen's AMD orders the m-block itself up to a few percent worse than its vertex graph: a margin
  constexpr double kMargin = 1.1;
  s.values = kMargin * dd * dd * static_cast<double>(L.nonZeros());
  s.row_indices = s.values;
  for (Eigen::Index j = 0; j < L.outerSize(); ++j) {
    const double c = static_cast<double>(L.outerIndexPtr()[j + 1] - L.outerIndexPtr()[j]);
    s.flops += dd * dd * dd * c * c;
  }
  s.ordering = "AMD (Eigen)";
  return s;
}

bool uses_cholmod(const Options& o) {
  return o.factorization == Factorization::Cholmod ||
         (o.factorization == Factorization::Automatic && detail::cholmod_available());
}

}  // namespace

MemoryEstimate estimate_memory(const Eigen::Ref<const Eigen::MatrixXd>& U,
                               const Eigen::Ref<const Eigen::MatrixXi>& T, long long dense_points,
                               const Options& options) {
  detail::check_shapes(U, T);
  if (dense_points < 0) throw Error("memory estimate: dense_points must be >= 0, got " + std::to_string(dense_points));
  const int d = static_cast<int>(U.cols()), n = static_cast<int>(U.rows());
  const Eigen::MatrixXi Tm = T;
  // vertices with unknowns: those of some element, less the boundary with pin_boundary
  std::vector<int> index(n, -1);
  for (Eigen::Index e = 0; e < Tm.rows(); ++e)
    for (int k = 0; k <= d; ++k) index[Tm(e, k)] = 0;
  if (options.pin_boundary) {
    const Eigen::VectorXi b = boundary_vertices(n, Tm);
    for (int i = 0; i < n; ++i)
      if (b(i)) index[i] = -1;
  }
  int kept = 0;
  for (int& i : index)
    if (i == 0) i = kept++;
  const VertexGraph G = vertex_graph(Tm, index, kept);
  const bool cholmod = uses_cholmod(options) && detail::cholmod_available();
  Symbolic s;
  if (kept > 0) {
#ifdef MBI_HAVE_CHOLMOD
    s = cholmod ? analyse_cholmod(G, d) : analyse_eigen(G, d);
#else
    s = analyse_eigen(G, d);
#endif
  }
  const double dd = d, V = static_cast<double>(G.full_entries());
  const double p = static_cast<double>(dense_points), m = static_cast<double>(Tm.rows()), nv = n;
  MemoryEstimate e;
  e.unknowns = static_cast<long long>(d) * kept;
  e.matrix_nonzeros = static_cast<long long>(dd * dd * V);
  e.factor_nonzeros = static_cast<long long>(s.values);
  e.factor_flops = s.flops;
  e.ordering = kept > 0 ? s.ordering : "none";
  constexpr double kEntry = 12;  // a sparse entry: its value and its row index
  const double nA = dd * dd * V, mx = dd * V;
  // kept: L's values and row indices, the threaded sweeps' copy of the row indices, the
  // right-hand-side operator -beta R H_mx
  e.factor_bytes = 8 * s.values + (cholmod ? 8 : 4) * s.row_indices + kEntry * mx;
  // alive while the factor is computed: the Hessians (H_vibr,mm, H_disc,mm, H_disc,mx, H_disc,xx),
  // their restrictions to the unknowns (three), the matrix A, CHOLMOD's copy of A and its
  // permuted upper half, the largest supernodal update; Eigen's path copies L instead
  e.assembly_bytes = cholmod ? kEntry * (6.5 * nA + 2 * mx + V) + 8 * s.update_values
                             : kEntry * (5.5 * nA + 2 * mx + V) + 12 * s.values;
  const long long red = e.unknowns - static_cast<long long>(d + d * (d - 1) / 2);
  const bool dense = options.solve_path == SolvePath::Dense ||
                     (options.solve_path == SolvePath::Automatic && static_cast<double>(red) * nv <= double(1LL << 21));
  e.dense_operator_bytes = dense ? 8.0 * std::max(0LL, red) * nv : 0.0;
  // per point: rest positions and normals, faces, the embedding (element, d + 1 coordinates), the
  // frame's positions, normals and float copy; per element: the embedding's gradients and the
  // Bezier points; per vertex: rest and deformed positions, M and the solve's scratch
  const double K = (dd + 1) * (dd + 2) / 2;
  e.model_bytes = p * (8 * dd + 24 + 24 + 4 + 8 * (dd + 1) + 8 * dd + 24 + 12) +
                  m * (4 * (dd + 1) + 8 * (dd + 1) * dd + 8 * K * dd) + nv * (8 * dd * 4 + 8 * dd * dd * 2);
  e.process_bytes = 56.0 * 1024 * 1024;  // mbi deform of a 1,000-vertex cage, less the parts above
  e.peak_bytes = e.process_bytes + e.model_bytes + e.factor_bytes + e.assembly_bytes + e.dense_operator_bytes;
  return e;
}

double parse_memory_size(const std::string& text) {
  const auto bad = [&] {
    return Error("memory size '" + text + "': expected a number > 0 with an optional unit K, M, G or T "
                 "(powers of 1024; KiB/KB alike), e.g. 8G or 512M");
  };
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || !std::isfinite(v) || !(v > 0)) throw bad();
  std::string unit(end);
  for (char& ch : unit) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  if (unit.size() > 1 && unit.back() == 'B') unit.pop_back();
  if (unit.size() > 1 && unit.back() == 'I') unit.pop_back();
  double scale = 1;
  if (unit == "K") scale = 1024.0;
  else if (unit == "M") scale = 1024.0 * 1024;
  else if (unit == "G") scale = 1024.0 * 1024 * 1024;
  else if (unit == "T") scale = 1024.0 * 1024 * 1024 * 1024;
  else if (!unit.empty() && unit != "B") throw bad();
  const double bytes = v * scale;
  if (!(bytes >= 1) || bytes > 1e18) throw bad();
  return bytes;
}

std::string format_bytes(double bytes) {
  char b[48];
  if (bytes >= 1024.0 * 1024 * 1024) std::snprintf(b, sizeof b, "%.3g GiB", bytes / (1024.0 * 1024 * 1024));
  else std::snprintf(b, sizeof b, "%.3g MiB", bytes / (1024.0 * 1024));
  return b;
}

void check_memory(const MemoryEstimate& e, double limit, const std::string& limit_name, const std::string& where) {
  if (!(limit > 0) || e.peak_bytes <= limit) return;
  char nonzeros[32];
  std::snprintf(nonzeros, sizeof nonzeros, "%.1fM", static_cast<double>(e.factor_nonzeros) / 1e6);
  std::ostringstream s;
  s << where << ": the modified-BI precompute would need about " << format_bytes(e.peak_bytes)
    << " of memory, more than the " << format_bytes(limit) << " of " << limit_name << " (" << e.unknowns
    << " unknowns; its Cholesky factor holds " << nonzeros << " nonzeros, " << format_bytes(e.factor_bytes) << ", with the " << e.ordering << " ordering; the matrices "
    << "while it is computed " << format_bytes(e.assembly_bytes) << "; the dense model and the frames "
    << format_bytes(e.model_bytes);
  if (e.dense_operator_bytes > 0) s << "; the dense operator " << format_bytes(e.dense_operator_bytes);
  s << "): use a coarser control mesh (mbi cage -n with fewer vertices)"
    << (limit_name == "--max-memory" ? " or a larger --max-memory" : " or a machine with more memory");
  throw Error(s.str());
}

}  // namespace mbi::interp
