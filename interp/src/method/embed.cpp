// Point location in the control mesh with a uniform grid; nearest element for outside points.
#include <mbi/interp/embed.hpp>

#include "method/detail.hpp"
#include "runtime/threads.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <limits>
#include <vector>

namespace mbi::interp {
namespace {

using Vec3 = Eigen::Vector3d;  // 2D data uses z = 0: one code path for d = 2 and 3

// Squared distance from p to the simplex with `count` vertices v[0..count) (any dimension of
// simplex up to 3). Projects on the affine hull; if a barycentric coordinate is negative the
// closest point lies on a facet opposite a negative coordinate, so recurse on those facets.
double simplex_distance2(const Vec3& p, const std::array<Vec3, 4>& v, int count) {
  if (count == 1) return (p - v[0]).squaredNorm();
  const int s = count - 1;
  Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, 3> E(3, s);
  for (int k = 0; k < s; ++k) E.col(k) = v[k + 1] - v[0];
  const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3> G = E.transpose() * E;
  const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1> r = E.transpose() * (p - v[0]);
  const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1> lam = G.ldlt().solve(r);
  std::array<double, 4> b{};
  b[0] = 1.0 - lam.sum();
  for (int k = 0; k < s; ++k) b[k + 1] = lam(k);
  bool inside = true;
  for (int k = 0; k < count; ++k) inside = inside && b[k] >= 0;
  if (inside) {
    const Vec3 q = v[0] + E * lam;
    return (p - q).squaredNorm();
  }
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < count; ++k) {
    if (b[k] >= 0) continue;
    std::array<Vec3, 4> sub;
    int c = 0;
    for (int l = 0; l < count; ++l)
      if (l != k) sub[c++] = v[l];
    best = std::min(best, simplex_distance2(p, sub, count - 1));
  }
  return best;
}

struct Locator {
  int d = 3;
  Eigen::MatrixXd U;                 // n x 3 (z = 0 in 2D)
  Eigen::MatrixXi T;
  std::vector<Eigen::Matrix3d> inv;  // inverse edge matrices (top-left d x d used)
  // the same by rows beside the element's first vertex, in one place: what bary() reads
  struct Frame {
    std::array<double, 9> inv;
    std::array<double, 3> origin;
  };
  std::vector<Frame> frame;
  std::vector<Vec3> box_lo, box_hi;  // element bounding boxes (prune the nearest search)
  Vec3 lo = Vec3::Zero();
  double h = 1.0;
  std::array<int, 3> dims{1, 1, 1};
  std::vector<int> start, items;  // CSR: cell -> elements whose bounding box overlaps it

  int cell_index(int i, int j, int k) const { return (k * dims[1] + j) * dims[0] + i; }

  void bary(int e, const Vec3& p, double* b) const {
    const Frame& f = frame[static_cast<size_t>(e)];
    const double r[3] = {p(0) - f.origin[0], p(1) - f.origin[1], p(2) - f.origin[2]};
    double sum = 0;
    for (int a = 0; a < d; ++a) {
      double v = 0;
      for (int c = 0; c < d; ++c) v += f.inv[static_cast<size_t>(3 * a + c)] * r[c];
      b[a + 1] = v;
      sum += v;
    }
    b[0] = 1.0 - sum;
  }

  // The smallest barycentric coordinate of p in element e (>= 0: p is in e).
  double min_bary(int e, const Vec3& p, double* b) const {
    bary(e, p, b);
    double mn = b[0];
    for (int k = 1; k <= d; ++k) mn = std::min(mn, b[k]);
    return mn;
  }

  double distance2(int e, const Vec3& p) const {
    std::array<Vec3, 4> v;
    for (int k = 0; k <= d; ++k) v[k] = U.row(T(e, k)).transpose();
    return simplex_distance2(p, v, d + 1);
  }

  std::array<int, 3> cell_of(const Vec3& p) const {
    std::array<int, 3> c{0, 0, 0};
    for (int a = 0; a < d; ++a) {
      const double f = std::floor((p(a) - lo(a)) / h);
      c[a] = static_cast<int>(std::clamp(f, 0.0, static_cast<double>(dims[a] - 1)));
    }
    return c;
  }
};

Locator build_locator(const Eigen::Ref<const Eigen::MatrixXd>& U0,
                      const Eigen::Ref<const Eigen::MatrixXi>& T) {
  Locator L;
  L.d = static_cast<int>(U0.cols());
  const int d = L.d;
  const int n = static_cast<int>(U0.rows());
  const int m = static_cast<int>(T.rows());
  L.U = Eigen::MatrixXd::Zero(n, 3);
  L.U.leftCols(d) = U0;
  L.T = T;
  L.inv.resize(m);
  L.frame.resize(m);
  L.box_lo.resize(m);
  L.box_hi.resize(m);
  for (int e = 0; e < m; ++e) {
    Eigen::MatrixXd E(d, d);
    for (int k = 0; k < d; ++k) E.col(k) = (U0.row(T(e, k + 1)) - U0.row(T(e, 0))).transpose();
    Eigen::FullPivLU<Eigen::MatrixXd> lu(E);
    if (!lu.isInvertible()) throw Error("element " + std::to_string(e) + " is degenerate");
    L.inv[e].setZero();
    L.inv[e].topLeftCorner(d, d) = lu.inverse();
    for (int a = 0; a < 3; ++a) {
      for (int c = 0; c < 3; ++c) L.frame[e].inv[static_cast<size_t>(3 * a + c)] = L.inv[e](a, c);
      L.frame[e].origin[static_cast<size_t>(a)] = L.U(T(e, 0), a);
    }
  }
  Vec3 hi = Vec3::Zero();
  L.lo.head(d) = U0.colwise().minCoeff().transpose();
  hi.head(d) = U0.colwise().maxCoeff().transpose();
  const Vec3 ext = hi - L.lo;
  // U is normalised by embed() (largest extent 1), so these sizes cannot under- or overflow; a
  // flat axis counts as 1e-3 of the largest one for the cell size.
  const double ext_max = ext.head(d).maxCoeff();
  double vol = 1;
  for (int a = 0; a < d; ++a) vol *= std::max(ext(a), 1e-3 * ext_max);
  // About 8 cells per element (a point meets few bounding boxes), at most 2^22 cells (a bounded
  // number of enlargements).
  L.h = std::pow(vol / (8.0 * std::max(m, 1)), 1.0 / d);
  for (int grow = 0;; ++grow) {
    double total = 1;
    for (int a = 0; a < d; ++a) total *= std::max(1.0, std::ceil(ext(a) / L.h));
    if (total <= static_cast<double>(1LL << 22) || grow > 200) break;
    L.h *= 1.5;
  }
  for (int a = 0; a < d; ++a)
    L.dims[a] = static_cast<int>(std::clamp(std::ceil(ext(a) / L.h), 1.0, static_cast<double>(1 << 22)));
  const long long cells = static_cast<long long>(L.dims[0]) * L.dims[1] * L.dims[2];
  std::vector<std::array<int, 6>> range(m);
  std::vector<int> count(static_cast<size_t>(cells) + 1, 0);
  for (int e = 0; e < m; ++e) {
    Vec3 a = L.U.row(T(e, 0)).transpose(), b = a;
    for (int k = 1; k <= d; ++k) {
      a = a.cwiseMin(L.U.row(T(e, k)).transpose());
      b = b.cwiseMax(L.U.row(T(e, k)).transpose());
    }
    L.box_lo[e] = a;
    L.box_hi[e] = b;
    const auto ca = L.cell_of(a), cb = L.cell_of(b);
    range[e] = {ca[0], ca[1], ca[2], cb[0], cb[1], cb[2]};
    for (int k = ca[2]; k <= cb[2]; ++k)
      for (int j = ca[1]; j <= cb[1]; ++j)
        for (int i = ca[0]; i <= cb[0]; ++i) ++count[L.cell_index(i, j, k) + 1];
  }
  for (long long c = 0; c < cells; ++c) count[c + 1] += count[c];
  L.start = count;
  L.items.resize(count[cells]);
  std::vector<int> fill(count.begin(), count.end() - 1);
  for (int e = 0; e < m; ++e) {
    const auto& r = range[e];
    for (int k = r[2]; k <= r[5]; ++k)
      for (int j = r[1]; j <= r[4]; ++j)
        for (int i = r[0]; i <= r[3]; ++i) L.items[fill[L.cell_index(i, j, k)]++] = e;
  }
  return L;
}

constexpr double kInsideTol = 1e-9;

// Locates one point: returns the element; sets distance (0 when inside). hint: an element to
// try first (the previous point's: neighbouring points of a model mostly share elements), or -1.
int locate(const Locator& L, const Vec3& p, int hint, std::vector<int>& stamp, int tag, double* b,
           double& distance) {
  const int d = L.d;
  distance = 0;
  if (hint >= 0 && L.min_bary(hint, p, b) >= 0) return hint;
  const auto c = L.cell_of(p);
  // 1. containing element: the first in p's cell that holds p, else the one with the largest
  // minimum coordinate when that is within the tolerance
  bool in_box = true;
  for (int a = 0; a < d; ++a)
    in_box = in_box && p(a) >= L.lo(a) - L.h * 1e-9 && p(a) <= L.lo(a) + L.dims[a] * L.h * (1 + 1e-9);
  int best = -1;
  double best_min = -std::numeric_limits<double>::infinity();
  if (in_box) {
    const int cell = L.cell_index(c[0], c[1], c[2]);
    std::array<double, 4> bb{};
    for (int s = L.start[cell]; s < L.start[cell + 1]; ++s) {
      const int e = L.items[s];
      const double mn = L.min_bary(e, p, bb.data());
      if (mn >= 0) {
        std::copy(bb.begin(), bb.begin() + d + 1, b);
        return e;
      }
      if (mn > best_min) {
        best_min = mn;
        best = e;
      }
    }
    if (best >= 0 && best_min >= -kInsideTol) {
      L.bary(best, p, b);
      return best;
    }
  }
  // 2. nearest element: shells of cells at Chebyshev distance k around p's (clamped) cell
  best = -1;
  double best_d2 = std::numeric_limits<double>::infinity();
  auto visit = [&](int i, int j, int kk) {
    const int cell = L.cell_index(i, j, kk);
    for (int s = L.start[cell]; s < L.start[cell + 1]; ++s) {
      const int e = L.items[s];
      if (stamp[e] == tag) continue;
      stamp[e] = tag;
      // the distance to the bounding box is a lower bound of the distance to the element
      const Vec3 q = p.cwiseMax(L.box_lo[e]).cwiseMin(L.box_hi[e]);
      if ((p - q).squaredNorm() > best_d2) continue;
      const double d2 = L.distance2(e, p);
      if (d2 < best_d2 || (d2 == best_d2 && e < best)) {
        best_d2 = d2;
        best = e;
      }
    }
  };
  const int maxk = std::max({L.dims[0], L.dims[1], L.dims[2]});
  for (int k = 0; k <= maxk; ++k) {
    std::array<int, 3> lo{0, 0, 0}, hi{0, 0, 0};
    for (int a = 0; a < d; ++a) {
      lo[a] = std::max(0, c[a] - k);
      hi[a] = std::min(L.dims[a] - 1, c[a] + k);
    }
    auto on_shell = [&](int a, int v) { return std::abs(v - c[a]) == k; };
    for (int i = lo[0]; i <= hi[0]; ++i) {
      if (d == 2) {
        if (on_shell(0, i)) {
          for (int j = lo[1]; j <= hi[1]; ++j) visit(i, j, 0);
        } else {
          if (c[1] - k >= 0) visit(i, c[1] - k, 0);
          if (k > 0 && c[1] + k < L.dims[1]) visit(i, c[1] + k, 0);
        }
        continue;
      }
      for (int j = lo[1]; j <= hi[1]; ++j) {
        if (on_shell(0, i) || on_shell(1, j)) {
          for (int kk = lo[2]; kk <= hi[2]; ++kk) visit(i, j, kk);
        } else {
          if (c[2] - k >= 0) visit(i, j, c[2] - k);
          if (k > 0 && c[2] + k < L.dims[2]) visit(i, j, c[2] + k);
        }
      }
    }
    // Every element not seen yet lies outside the box of cells [c-k, c+k]: bound its distance.
    double bound = std::numeric_limits<double>::infinity();
    for (int a = 0; a < d; ++a) {
      if (c[a] - k > 0) bound = std::min(bound, p(a) - (L.lo(a) + (c[a] - k) * L.h));
      if (c[a] + k < L.dims[a] - 1) bound = std::min(bound, L.lo(a) + (c[a] + k + 1) * L.h - p(a));
    }
    if (best >= 0 && best_d2 <= bound * bound) break;
    if (bound == std::numeric_limits<double>::infinity()) break;
  }
  if (best < 0) return -1;  // no finite distance: embed() reports the point
  L.bary(best, p, b);
  distance = std::sqrt(best_d2);
  return best;
}

// Points farther than this from the control mesh's bounding box, in units of its largest
// extent, are refused: extrapolation from there means nothing, and the nearest-element search
// works with squared distances (kFarLimit^2 = 1e24 stays far from overflow).
constexpr double kFarLimit = 1e12;

std::string format_g(double x) {
  char b[40];
  std::snprintf(b, sizeof b, "%.6g", x);
  return b;
}

}  // namespace

Embedding embed(const Eigen::Ref<const Eigen::MatrixXd>& U,
                const Eigen::Ref<const Eigen::MatrixXi>& T,
                const Eigen::Ref<const Eigen::MatrixXd>& P) {
  detail::check_shapes(U, T);
  detail::check_finite("control vertex", U);
  const int d = static_cast<int>(U.cols());
  if (P.cols() != d)
    throw Error("points must be p x " + std::to_string(d) + " like the control mesh, got p x " +
                std::to_string(P.cols()));
  detail::check_finite("point", P);
  // Scale-free: the control mesh and the points are moved to the centre of the mesh's bounding
  // box and scaled by its largest extent s (halves first: no overflow even at +-1e308). The
  // coordinates are affine invariants; distances and gradients are mapped back below.
  const Eigen::RowVectorXd lo = U.colwise().minCoeff(), hi = U.colwise().maxCoeff();
  const Eigen::RowVectorXd center = 0.5 * lo + 0.5 * hi;
  const double s = 2.0 * (0.5 * hi - 0.5 * lo).maxCoeff();
  if (!(s > 0) || !std::isfinite(s))
    throw Error("the control mesh has no extent (every vertex at the same point)");
  const Eigen::MatrixXd Un = (U.rowwise() - center) / s;
  Eigen::MatrixXd Pn = (P.rowwise() - center) / s;
  for (Eigen::Index i = 0; i < Pn.rows(); ++i) {
    const double far = Pn.row(i).cwiseAbs().maxCoeff();
    if (!(far <= kFarLimit)) {  // also NaN/inf from (p - centre) / s overflowing
      std::string at;
      for (int c = 0; c < d; ++c) at += (c ? ", " : "") + format_g(P(i, c));
      throw Error("point " + std::to_string(i) + " (" + at + ") lies more than " +
                  format_g(kFarLimit) + " times the control mesh's size (" + format_g(s) +
                  ") away from it: too far to extrapolate");
    }
  }
  const Locator L = build_locator(Un, T);
  const int np = static_cast<int>(P.rows());
  const int m = static_cast<int>(T.rows());

  Embedding emb;
  emb.element.resize(np);
  emb.bary.resize(np, d + 1);
  Eigen::VectorXd dist(np);
  // blocks of points to whichever thread asks; each thread keeps its own search stamps
  detail::Blocks blocks(np, 4096);
  detail::run_shared(detail::thread_count(np, 4096), [&] {
    std::vector<int> stamp(m, -1);
    std::array<double, 4> bb{};
    for (long long b, e; blocks.next(b, e);) {
      int hint = -1;
      for (long long i = b; i < e; ++i) {
        Vec3 p = Vec3::Zero();
        p.head(d) = Pn.row(i).transpose();
        double dd = 0;
        bb.fill(0.0);
        const int el = locate(L, p, hint, stamp, static_cast<int>(i), bb.data(), dd);
        hint = dd == 0 ? el : -1;
        emb.element(i) = el;
        for (int k = 0; k <= d; ++k) emb.bary(i, k) = bb[k];
        dist(i) = dd;
      }
    }
  });
  for (int i = 0; i < np; ++i) {
    if (emb.element(i) < 0 || !emb.bary.row(i).allFinite())  // never index element -1
      throw Error("point " + std::to_string(i) + ": no element found (distance overflow)");
    if (dist(i) > 0 || emb.bary.row(i).minCoeff() < -kInsideTol) {
      emb.outside.push_back(i);
      emb.outside_distance.push_back(dist(i) * s);
      emb.max_outside_distance = std::max(emb.max_outside_distance, dist(i) * s);
    }
  }
  emb.gradients.resize(static_cast<Eigen::Index>(m) * (d + 1), d);
  for (int e = 0; e < m; ++e) {
    const Eigen::Matrix3d inv = L.inv[e] / s;  // gradients in the input's units
    for (int k = 0; k < d; ++k) emb.gradients.row(e * (d + 1) + k + 1) = inv.row(k).head(d);
    emb.gradients.row(e * (d + 1)) = -inv.topLeftCorner(d, d).colwise().sum();
  }
  if (!emb.gradients.allFinite())
    throw Error("the control mesh is too small (size " + format_g(s) +
                "): its basis gradients overflow");
  return emb;
}

Eigen::MatrixXd embedded_positions(const Eigen::Ref<const Eigen::MatrixXd>& U,
                                   const Eigen::Ref<const Eigen::MatrixXi>& T,
                                   const Embedding& emb) {
  detail::check_shapes(U, T);
  const int d = static_cast<int>(U.cols());
  if (emb.bary.cols() != d + 1 || emb.bary.rows() != emb.element.size())
    throw Error("embedding has " + std::to_string(emb.bary.cols()) +
                " coordinates per point, expected " + std::to_string(d + 1));
  Eigen::MatrixXd out(emb.size(), d);
  for (int i = 0; i < emb.size(); ++i) {
    const int e = emb.element(i);
    if (e < 0 || e >= T.rows())
      throw Error("point " + std::to_string(i) + " refers to element " +
                  std::to_string(e) + " outside [0, " + std::to_string(T.rows()) + ")");
    out.row(i).setZero();
    for (int k = 0; k <= d; ++k) out.row(i) += emb.bary(i, k) * U.row(T(e, k));
  }
  return out;
}

}  // namespace mbi::interp
