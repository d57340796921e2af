// Control-mesh generation: voxel envelope + Kuhn subdivision, or its boundary meshed by TetGen
// (see cage.hpp; TetGen itself is called in tetrahedralize.cpp).
#include <mbi/interp/embed.hpp>
#include <mbi/generate/cage.hpp>

#include "tetrahedralize.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace mbi::generate {
namespace {

constexpr long long kMaxCells = 32LL * 1024 * 1024;
// A model whose extent is below this fraction of its distance from the origin is refused: its
// coordinates have too few significant digits left for a cage (1e-9: about 7 digits remain).
constexpr double kMinRelativeExtent = 1e-9;

CageResult make_cage_normalised(const Eigen::MatrixXd& P, const Eigen::MatrixXi& Fi,
                                const CageOptions& options, int d);

/// Occupied cells of a uniform grid (d = 2: nz = 1).
struct Grid {
  int d = 3;
  std::array<double, 3> h{1.0, 1.0, 1.0};  // cell edge per axis
  std::array<double, 3> origin{};
  std::array<long long, 3> n{1, 1, 1};
  std::vector<std::uint8_t> occ;  // 1 = touched by the surface, 2 = enclosed, 0 = empty
  long long index(long long i, long long j, long long k) const { return i + n[0] * (j + n[1] * k); }
  long long cells() const { return n[0] * n[1] * n[2]; }
};

bool tri_box_overlap_3d(const std::array<Eigen::Vector3d, 3>& tri, const Eigen::Vector3d& c,
                        const Eigen::Vector3d& hs) {
  const Eigen::Vector3d v0 = tri[0] - c, v1 = tri[1] - c, v2 = tri[2] - c;
  for (int a = 0; a < 3; ++a) {
    const double mn = std::min({v0(a), v1(a), v2(a)}), mx = std::max({v0(a), v1(a), v2(a)});
    if (mn > hs(a) || mx < -hs(a)) return false;
  }
  const std::array<Eigen::Vector3d, 3> e{Eigen::Vector3d(v1 - v0), Eigen::Vector3d(v2 - v1),
                                         Eigen::Vector3d(v0 - v2)};
  auto separated = [&](const Eigen::Vector3d& ax) {
    const double p0 = ax.dot(v0), p1 = ax.dot(v1), p2 = ax.dot(v2);
    const double r = hs(0) * std::abs(ax(0)) + hs(1) * std::abs(ax(1)) + hs(2) * std::abs(ax(2));
    return std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r;
  };
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      Eigen::Vector3d unit = Eigen::Vector3d::Zero();
      unit(j) = 1.0;
      const Eigen::Vector3d ax = e[static_cast<std::size_t>(i)].cross(unit);
      if (separated(ax)) return false;
    }
  const Eigen::Vector3d nrm = e[0].cross(e[1]);
  return !separated(nrm);
}

bool tri_box_overlap_2d(const std::array<Eigen::Vector2d, 3>& tri, const Eigen::Vector2d& c,
                        const Eigen::Vector2d& hs) {
  std::array<Eigen::Vector2d, 3> v{Eigen::Vector2d(tri[0] - c), Eigen::Vector2d(tri[1] - c),
                                   Eigen::Vector2d(tri[2] - c)};
  for (int a = 0; a < 2; ++a) {
    const double mn = std::min({v[0](a), v[1](a), v[2](a)});
    const double mx = std::max({v[0](a), v[1](a), v[2](a)});
    if (mn > hs(a) || mx < -hs(a)) return false;
  }
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector2d e = v[static_cast<std::size_t>((i + 1) % 3)] - v[static_cast<std::size_t>(i)];
    const Eigen::Vector2d ax(-e(1), e(0));
    const double p0 = ax.dot(v[0]), p1 = ax.dot(v[1]), p2 = ax.dot(v[2]);
    const double r = hs(0) * std::abs(ax(0)) + hs(1) * std::abs(ax(1));
    if (std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r) return false;
  }
  return true;
}

/// Voxelises the surface for cell edges h (per axis). Returns false if the grid would be too
/// large.
bool voxelise(const Eigen::MatrixXd& P, const Eigen::MatrixXi& F, int d,
              const std::array<double, 3>& h, Grid& g, long long max_cells = kMaxCells) {
  g = Grid{};
  g.d = d;
  g.h = h;
  const Eigen::VectorXd lo = P.colwise().minCoeff().transpose();
  const Eigen::VectorXd hi = P.colwise().maxCoeff().transpose();
  long double cells = 1;
  for (int c = 0; c < d; ++c) {
    const double ext = hi(c) - lo(c);
    const double hc = h[static_cast<std::size_t>(c)];
    const double nc = std::floor(ext / hc) + 1.0;
    if (!(nc <= 1e7)) return false;  // also NaN (h underflowed to 0)
    g.n[static_cast<std::size_t>(c)] = static_cast<long long>(nc);
    g.origin[static_cast<std::size_t>(c)] = lo(c) - 0.5 * (nc * hc - ext);
    cells *= nc;
  }
  // Estimated before allocating: about 10 bytes per cell (occupancy, outside flags, fill stack).
  if (cells > static_cast<long double>(std::min(max_cells, kMaxCells))) return false;
  g.occ.assign(static_cast<std::size_t>(g.cells()), 0);
  auto cell_of = [&](double x, int c) {
    const auto i = static_cast<long long>(std::floor((x - g.origin[static_cast<std::size_t>(c)]) /
                                                     h[static_cast<std::size_t>(c)]));
    return std::clamp<long long>(i, 0, g.n[static_cast<std::size_t>(c)] - 1);
  };
  // Every vertex's cell (also vertices that no face uses).
  for (Eigen::Index v = 0; v < P.rows(); ++v) {
    std::array<long long, 3> ijk{0, 0, 0};
    for (int c = 0; c < d; ++c) ijk[static_cast<std::size_t>(c)] = cell_of(P(v, c), c);
    g.occ[static_cast<std::size_t>(g.index(ijk[0], ijk[1], ijk[2]))] = 1;
  }
  // Every cell that a triangle touches (conservative: the box is enlarged by a hair).
  const Eigen::Vector3d hs3 = 0.5 * (1.0 + 1e-6) * Eigen::Vector3d(h[0], h[1], h[2]);
  const Eigen::Vector2d hs2 = hs3.head<2>();
  for (Eigen::Index t = 0; t < F.rows(); ++t) {
    std::array<long long, 3> a{0, 0, 0}, b{0, 0, 0};
    for (int c = 0; c < d; ++c) {
      const double mn = std::min({P(F(t, 0), c), P(F(t, 1), c), P(F(t, 2), c)});
      const double mx = std::max({P(F(t, 0), c), P(F(t, 1), c), P(F(t, 2), c)});
      a[static_cast<std::size_t>(c)] = cell_of(mn - 1e-6 * h[static_cast<std::size_t>(c)], c);
      b[static_cast<std::size_t>(c)] = cell_of(mx + 1e-6 * h[static_cast<std::size_t>(c)], c);
    }
    if (d == 3) {
      const std::array<Eigen::Vector3d, 3> tri{P.row(F(t, 0)).transpose(),
                                               P.row(F(t, 1)).transpose(),
                                               P.row(F(t, 2)).transpose()};
      for (long long k = a[2]; k <= b[2]; ++k)
        for (long long j = a[1]; j <= b[1]; ++j)
          for (long long i = a[0]; i <= b[0]; ++i) {
            auto& o = g.occ[static_cast<std::size_t>(g.index(i, j, k))];
            if (o) continue;
            const Eigen::Vector3d c(g.origin[0] + (static_cast<double>(i) + 0.5) * h[0],
                                    g.origin[1] + (static_cast<double>(j) + 0.5) * h[1],
                                    g.origin[2] + (static_cast<double>(k) + 0.5) * h[2]);
            if (tri_box_overlap_3d(tri, c, hs3)) o = 1;
          }
    } else {
      const std::array<Eigen::Vector2d, 3> tri{P.row(F(t, 0)).transpose(),
                                               P.row(F(t, 1)).transpose(),
                                               P.row(F(t, 2)).transpose()};
      for (long long j = a[1]; j <= b[1]; ++j)
        for (long long i = a[0]; i <= b[0]; ++i) {
          auto& o = g.occ[static_cast<std::size_t>(g.index(i, j, 0))];
          if (o) continue;
          const Eigen::Vector2d c(g.origin[0] + (static_cast<double>(i) + 0.5) * h[0],
                                  g.origin[1] + (static_cast<double>(j) + 0.5) * h[1]);
          if (tri_box_overlap_2d(tri, c, hs2)) o = 1;
        }
    }
  }
  // 3D: enclosed cells (the solid inside a closed surface) are everything a 6-connected flood
  // fill from the grid border cannot reach. 2D input is already a filled region: its holes stay.
  if (d == 2) return true;
  std::vector<std::uint8_t> outside(g.occ.size(), 0);
  std::vector<long long> stack;
  auto seed = [&](long long i, long long j, long long k) {
    const long long id = g.index(i, j, k);
    if (!g.occ[static_cast<std::size_t>(id)] && !outside[static_cast<std::size_t>(id)]) {
      outside[static_cast<std::size_t>(id)] = 1;
      stack.push_back(id);
    }
  };
  for (long long k = 0; k < g.n[2]; ++k)
    for (long long j = 0; j < g.n[1]; ++j)
      for (long long i = 0; i < g.n[0]; ++i) {
        const bool border = i == 0 || j == 0 || i == g.n[0] - 1 || j == g.n[1] - 1 ||
                            (d == 3 && (k == 0 || k == g.n[2] - 1));
        if (border) seed(i, j, k);
      }
  while (!stack.empty()) {
    const long long id = stack.back();
    stack.pop_back();
    const long long i = id % g.n[0], j = (id / g.n[0]) % g.n[1], k = id / (g.n[0] * g.n[1]);
    if (i > 0) seed(i - 1, j, k);
    if (i + 1 < g.n[0]) seed(i + 1, j, k);
    if (j > 0) seed(i, j - 1, k);
    if (j + 1 < g.n[1]) seed(i, j + 1, k);
    if (d == 3 && k > 0) seed(i, j, k - 1);
    if (d == 3 && k + 1 < g.n[2]) seed(i, j, k + 1);
  }
  for (std::size_t c = 0; c < g.occ.size(); ++c)
    if (!g.occ[c] && !outside[c]) g.occ[c] = 2;
  return true;
}

/// Lattice-point ids of the occupied cells' corners, in lexicographic (k, j, i) order.
std::vector<int> corner_ids(const Grid& g, int& count) {
  const long long px = g.n[0] + 1, py = g.n[1] + 1, pz = g.d == 3 ? g.n[2] + 1 : 1;
  std::vector<int> id(static_cast<std::size_t>(px * py * pz), -1);
  const int kc = g.d == 3 ? 2 : 1;
  for (long long k = 0; k < g.n[2]; ++k)
    for (long long j = 0; j < g.n[1]; ++j)
      for (long long i = 0; i < g.n[0]; ++i) {
        if (!g.occ[static_cast<std::size_t>(g.index(i, j, k))]) continue;
        for (int c = 0; c < 4 * kc; ++c) {
          const long long a = i + (c & 1), b = j + ((c >> 1) & 1), z = k + ((c >> 2) & 1);
          id[static_cast<std::size_t>(a + px * (b + py * z))] = 0;
        }
      }
  count = 0;
  for (auto& v : id)
    if (v == 0) v = count++;
  return id;
}

int count_vertices(const Grid& g) {
  int n = 0;
  corner_ids(g, n);
  return n;
}

double simplex_volume(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T, Eigen::Index e) {
  const int d = static_cast<int>(U.cols());
  Eigen::MatrixXd E(d, d);
  for (int k = 0; k < d; ++k) E.col(k) = (U.row(T(e, k + 1)) - U.row(T(e, 0))).transpose();
  return E.determinant();
}

void build_mesh(const Grid& g, Eigen::MatrixXd& U, Eigen::MatrixXi& T) {
  int n = 0;
  const std::vector<int> id = corner_ids(g, n);
  const long long px = g.n[0] + 1, py = g.n[1] + 1, pz = g.d == 3 ? g.n[2] + 1 : 1;
  U.resize(n, g.d);
  for (long long z = 0; z < pz; ++z)
    for (long long b = 0; b < py; ++b)
      for (long long a = 0; a < px; ++a) {
        const int v = id[static_cast<std::size_t>(a + px * (b + py * z))];
        if (v < 0) continue;
        const std::array<long long, 3> l{a, b, z};
        for (int c = 0; c < g.d; ++c)
          U(v, c) = g.origin[static_cast<std::size_t>(c)] +
                    static_cast<double>(l[static_cast<std::size_t>(c)]) * g.h[static_cast<std::size_t>(c)];
      }
  long long occupied = 0;
  for (auto o : g.occ) occupied += o != 0;
  const int per = g.d == 3 ? 6 : 2;
  T.resize(static_cast<Eigen::Index>(occupied * per), g.d + 1);
  auto corner = [&](long long i, long long j, long long k, int dx, int dy, int dz) {
    return id[static_cast<std::size_t>((i + dx) + px * ((j + dy) + py * (k + dz)))];
  };
  static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  Eigen::Index r = 0;
  for (long long k = 0; k < g.n[2]; ++k)
    for (long long j = 0; j < g.n[1]; ++j)
      for (long long i = 0; i < g.n[0]; ++i) {
        if (!g.occ[static_cast<std::size_t>(g.index(i, j, k))]) continue;
        if (g.d == 3) {
          for (const auto& p : perms) {  // Kuhn: paths 000 -> 111 along the axes in order p
            std::array<int, 3> s{0, 0, 0};
            T(r, 0) = corner(i, j, k, 0, 0, 0);
            for (int step = 0; step < 3; ++step) {
              s[static_cast<std::size_t>(p[step])] = 1;
              T(r, step + 1) = corner(i, j, k, s[0], s[1], s[2]);
            }
            ++r;
          }
        } else {
          T(r, 0) = corner(i, j, 0, 0, 0, 0);
          T(r, 1) = corner(i, j, 0, 1, 0, 0);
          T(r, 2) = corner(i, j, 0, 1, 1, 0);
          ++r;
          T(r, 0) = corner(i, j, 0, 0, 0, 0);
          T(r, 1) = corner(i, j, 0, 1, 1, 0);
          T(r, 2) = corner(i, j, 0, 0, 1, 0);
          ++r;
        }
      }
  for (Eigen::Index e = 0; e < T.rows(); ++e)
    if (simplex_volume(U, T, e) < 0) std::swap(T(e, 0), T(e, 1));
}

/// Boundary of the union of the occupied cells (3D): every cell face whose neighbour is empty
/// or outside the grid, as two triangles split along the diagonal through the face's lowest
/// lattice corner. Vertices are the lattice points used, numbered in lexicographic (k, j, i)
/// order. Returns the vertex count; fills X (n x 3) and B (t x 3) if asked.
int envelope_boundary(const Grid& g, Eigen::MatrixXd* X, std::vector<std::array<int, 3>>* B) {
  const long long px = g.n[0] + 1, py = g.n[1] + 1, pz = g.n[2] + 1;
  auto occupied = [&](long long i, long long j, long long k) {
    if (i < 0 || j < 0 || k < 0 || i >= g.n[0] || j >= g.n[1] || k >= g.n[2]) return false;
    return g.occ[static_cast<std::size_t>(g.index(i, j, k))] != 0;
  };
  auto lattice = [&](long long a, long long b, long long c) { return a + px * (b + py * c); };
  std::vector<int> id(static_cast<std::size_t>(px * py * pz), -1);
  std::vector<std::array<long long, 4>> quads;  // lattice ids: corner, +u, +u+w, +w
  for (long long k = 0; k < g.n[2]; ++k)
    for (long long j = 0; j < g.n[1]; ++j)
      for (long long i = 0; i < g.n[0]; ++i) {
        if (!occupied(i, j, k)) continue;
        for (int axis = 0; axis < 3; ++axis)
          for (int side = 0; side < 2; ++side) {
            std::array<long long, 3> nb{i, j, k};
            nb[static_cast<std::size_t>(axis)] += side ? 1 : -1;
            if (occupied(nb[0], nb[1], nb[2])) continue;
            const int u = (axis + 1) % 3, w = (axis + 2) % 3;
            std::array<long long, 3> c0{i, j, k};
            c0[static_cast<std::size_t>(axis)] += side;
            std::array<long long, 3> cu = c0, cuw = c0, cw = c0;
            cu[static_cast<std::size_t>(u)] += 1;
            cuw[static_cast<std::size_t>(u)] += 1;
            cuw[static_cast<std::size_t>(w)] += 1;
            cw[static_cast<std::size_t>(w)] += 1;
            std::array<long long, 4> q{lattice(c0[0], c0[1], c0[2]), lattice(cu[0], cu[1], cu[2]),
                                       lattice(cuw[0], cuw[1], cuw[2]), lattice(cw[0], cw[1], cw[2])};
            if (side == 0) std::swap(q[1], q[3]);  // outward orientation
            for (long long v : q) id[static_cast<std::size_t>(v)] = 0;
            quads.push_back(q);
          }
      }
  int count = 0;
  for (auto& v : id)
    if (v == 0) v = count++;
  if (X) {
    X->resize(count, 3);
    for (long long z = 0; z < pz; ++z)
      for (long long b = 0; b < py; ++b)
        for (long long a = 0; a < px; ++a) {
          const int v = id[static_cast<std::size_t>(lattice(a, b, z))];
          if (v < 0) continue;
          (*X)(v, 0) = g.origin[0] + static_cast<double>(a) * g.h[0];
          (*X)(v, 1) = g.origin[1] + static_cast<double>(b) * g.h[1];
          (*X)(v, 2) = g.origin[2] + static_cast<double>(z) * g.h[2];
        }
  }
  if (B) {
    B->clear();
    for (const auto& q : quads) {
      const auto at = [&](int c) { return id[static_cast<std::size_t>(q[static_cast<std::size_t>(c)])]; };
      B->push_back({at(0), at(1), at(2)});
      B->push_back({at(0), at(2), at(3)});
    }
  }
  return count;
}

/// Why TetGen must not see the envelope boundary X, B of grid g (empty: it may). The cage code
/// works on coordinates normalised to a unit box (make_cage), so lattice points lie within a
/// few cells of [-1, 1] and cells are at least 1e-8 wide: far inside the range where TetGen's
/// exact predicates and its relative epsilon (1e-8) work.
std::string tetgen_input_problem(const Eigen::MatrixXd& X, const std::vector<std::array<int, 3>>& B,
                                 const Grid& g) {
  if (X.rows() < 4 || B.size() < 4) return "fewer than 4 boundary points or facets";
  if (!X.allFinite()) return "a non-finite boundary point";
  if (X.cwiseAbs().maxCoeff() > 4.0) return "coordinates not normalised (largest " +
                                            std::to_string(X.cwiseAbs().maxCoeff()) + ")";
  for (int c = 0; c < 3; ++c)
    if (!(g.h[static_cast<std::size_t>(c)] >= 1e-8)) return "a cell narrower than 1e-8 of the model";
  for (const auto& t : B) {
    for (int c = 0; c < 3; ++c)
      if (t[static_cast<std::size_t>(c)] < 0 || t[static_cast<std::size_t>(c)] >= X.rows())
        return "a facet index out of range";
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return "a facet with a repeated corner";
    const Eigen::Vector3d a = X.row(t[0]).transpose(), b = X.row(t[1]).transpose(),
                          c = X.row(t[2]).transpose();
    if (!((b - a).cross(c - a).norm() > 0)) return "a facet of zero area";
  }
  return {};
}

/// Tetrahedralises the envelope boundary of g with TetGen. Returns false (reason in `why`) if
/// TetGen fails or the result does not keep the boundary vertices first and unchanged.
bool tetgen_envelope(const Grid& g, const std::string& switches, Eigen::MatrixXd& U,
                     Eigen::MatrixXi& T, std::string& why) {
  Eigen::MatrixXd X;
  std::vector<std::array<int, 3>> B;
  const int nb = envelope_boundary(g, &X, &B);
  // TetGen's fence: what reaches it is checked first (finite, normalised coordinates, distinct
  // in-range facet corners, facets of non-zero area), so its internal assertions cannot fire on
  // our input; and whatever it throws becomes a reason here.
  const std::string bad = tetgen_input_problem(X, B, g);
  if (!bad.empty()) {
    why = "TetGen input refused: " + bad;
    return false;
  }
  Eigen::MatrixXd points;
  Eigen::MatrixXi tets;
  if (!detail::tetrahedralize(X, B, switches, points, tets, why)) return false;
  if (points.rows() < nb || tets.rows() <= 0) {
    why = "TetGen -" + switches + " returned no tetrahedra";
    return false;
  }
  for (int v = 0; v < nb; ++v)
    for (int c = 0; c < 3; ++c)
      if (points(v, c) != X(v, c)) {
        why = "TetGen -" + switches + " moved a boundary vertex";
        return false;
      }
  // Keep only the vertices used by tetrahedra (in TetGen's order).
  std::vector<int> map(static_cast<std::size_t>(points.rows()), -1);
  for (Eigen::Index e = 0; e < 4 * tets.rows(); ++e) {
    const int v = tets(e / 4, e % 4);
    if (v < 0 || v >= points.rows()) {
      why = "TetGen -" + switches + " returned a bad vertex index";
      return false;
    }
    map[static_cast<std::size_t>(v)] = 0;
  }
  int n = 0;
  for (auto& m : map)
    if (m == 0) m = n++;
  U.resize(n, 3);
  for (Eigen::Index v = 0; v < points.rows(); ++v)
    if (map[static_cast<std::size_t>(v)] >= 0) U.row(map[static_cast<std::size_t>(v)]) = points.row(v);
  T.resize(tets.rows(), 4);
  for (Eigen::Index e = 0; e < tets.rows(); ++e)
    for (int c = 0; c < 4; ++c) T(e, c) = map[static_cast<std::size_t>(tets(e, c))];
  for (Eigen::Index e = 0; e < T.rows(); ++e) {
    const double vol = simplex_volume(U, T, e);
    if (vol == 0.0) {
      why = "TetGen -" + switches + " returned a flat tetrahedron";
      return false;
    }
    if (vol < 0) std::swap(T(e, 0), T(e, 1));
  }
  return true;
}

/// TetGen switch sets tried in turn on one envelope (all keep the boundary: p and Y).
const std::vector<std::string>& tetgen_switch_ladder() {
  // Measured on the bunny, spot and fandisk at 100 and 450 vertices: -q1.5 (radius-edge only)
  // gave the best smallest dihedral angles (7-24 deg) for a few interior points; no -q gave 5.3
  // deg at worst. A dihedral bound in -q (e.g. -q1.5/15 with -Y) can abort inside TetGen: never.
  static const std::vector<std::string> ladder{"pq1.5YzQ", "pq1.2YzQ", "pq2.0YzQ", "pYzQ"};
  return ladder;
}

// Cell-size search shared by both meshers: bracket from h0 downwards by halving until eval(h)
// (the vertex count at cell size h; every call is recorded by the caller) reaches the target,
// bisect in log h, then scan `steps` sizes within a factor `spread` either side, because the
// count is not monotone in h. The caller picks the best of what eval recorded. The number of
// evaluations is bounded (at most 60 + 8 + 30 + steps) and so is each one (eval returns INT_MAX for
// a grid over the cell cap, without allocating it). Returns false, with the largest count seen
// in `best_count`, when no cell size within the cap reaches the target: finer grids only add
// empty cells (a few points, parts far apart, one stray vertex far away).
template <typename Eval>
bool search_cell_size(Eval&& eval, double h0, int target, int steps, double spread, int& best_count) {
  double h_hi = h0, h_lo = h0;
  int c_lo = eval(h_lo);
  best_count = c_lo == std::numeric_limits<int>::max() ? 0 : c_lo;
  for (int it = 0; it < 60 && c_lo < target; ++it) {
    h_hi = h_lo;
    h_lo *= 0.5;
    c_lo = eval(h_lo);
    if (c_lo == std::numeric_limits<int>::max()) {
      // over the cap: the finest grids under it, between h_lo and h_hi (8 bisection steps), are
      // the last chance to reach the target
      bool reached = false;
      for (int b = 0; b < 8 && !reached; ++b) {
        const double h = std::sqrt(h_lo * h_hi);
        const int c = eval(h);
        if (c == std::numeric_limits<int>::max()) {
          h_lo = h;
        } else if (c >= target) {
          h_lo = h;
          c_lo = c;
          reached = true;
        } else {
          h_hi = h;
          best_count = std::max(best_count, c);
        }
      }
      if (!reached) return false;
      break;
    }
    best_count = std::max(best_count, c_lo);
  }
  if (c_lo < target) return false;
  for (int it = 0; it < 30 && c_lo != target; ++it) {
    const double h = std::sqrt(h_lo * h_hi);
    const int c = eval(h);
    if (c >= target)
      h_lo = h;
    else
      h_hi = h;
    if (h_hi / h_lo < 1.0 + 1e-4) break;
  }
  const double h_mid = std::sqrt(h_lo * h_hi);
  for (int s = 0; s < steps; ++s) eval(h_mid * std::pow(spread, -1.0 + 2.0 * (s + 0.5) / steps));
  return true;
}

// Cell cap of one grid for a target vertex count: generous for thin and diagonal shapes (a
// diagonal rod needs about 600 grid cells per cage vertex), bounded so that one evaluation
// stays below about 0.3 s and 320 MB (kMaxCells).
long long grid_cap(int target) {
  return std::clamp<long long>(4096LL * target, 1LL << 20, kMaxCells);
}

[[noreturn]] void unreachable_target(int target, int best, long long cap) {
  throw Error("cannot reach " + std::to_string(target) +
                  " control vertices: grids of up to " + std::to_string(cap) +
                  " cells give at most " + std::to_string(best) +
                  " (the model's bounding box is mostly empty: too few points, parts far apart or "
                  "a stray vertex far away); ask for fewer vertices or clean the model");
}

CageResult make_cage_tetgen(const Eigen::MatrixXd& P, const Eigen::MatrixXi& Fi,
                            const CageOptions& options) {
  const int target = options.target_vertices;
  const double scale = (P.colwise().maxCoeff() - P.colwise().minCoeff()).maxCoeff();  // 1: normalised
  const long long cap = grid_cap(target);
  struct Tried {
    double h;
    int count;  // boundary vertices
  };
  std::vector<Tried> tried;
  Grid g;
  auto eval = [&](double h) {
    const int c = voxelise(P, Fi, 3, {h, h, h}, g, cap) ? envelope_boundary(g, nullptr, nullptr)
                                                       : std::numeric_limits<int>::max();
    tried.push_back({h, c});
    return c;
  };
  // Search on the boundary vertex count (TetGen adds few vertices inside).
  int best_count = 0;
  if (!search_cell_size(eval, 1.01 * scale, target, options.search_steps, 1.5, best_count))
    unreachable_target(target, best_count, cap);
  std::stable_sort(tried.begin(), tried.end(), [](const Tried& a, const Tried& b) { return a.h > b.h; });

  // Run TetGen on the candidate whose boundary count plus the interior points seen so far is
  // closest to the target; keep the best qualifying mesh.
  CageResult best;
  long long best_dist = std::numeric_limits<long long>::max();
  std::string last_why = "no candidate cell size";
  double interior_est = 0.0;  // TetGen's interior vertices as a fraction of the boundary count
  std::vector<char> done(tried.size(), 0);
  const auto& ladder = tetgen_switch_ladder();
  for (int attempt = 0; attempt < 8; ++attempt) {
    std::size_t pick = tried.size();
    double pick_dist = std::numeric_limits<double>::max();
    for (std::size_t k = 0; k < tried.size(); ++k) {
      if (done[k] || tried[k].count == std::numeric_limits<int>::max()) continue;
      const double dist = std::abs(tried[k].count * (1.0 + interior_est) - target);
      if (dist < pick_dist) {
        pick_dist = dist;
        pick = k;
      }
    }
    if (pick == tried.size()) break;
    for (std::size_t k = 0; k < tried.size(); ++k)  // the same envelope under another h
      if (tried[k].count == tried[pick].count && std::abs(tried[k].h / tried[pick].h - 1) < 1e-12)
        done[k] = 1;
    done[pick] = 1;
    const double h = tried[pick].h;
    if (!voxelise(P, Fi, 3, {h, h, h}, g, cap)) continue;
    for (const std::string& sw : ladder) {
      CageResult r;
      std::string why;
      if (!tetgen_envelope(g, sw, r.U, r.T, why)) {
        last_why = why;
        continue;
      }
      interior_est = static_cast<double>(r.U.rows()) / tried[pick].count - 1.0;
      r.min_dihedral_deg = min_dihedral_angle_deg(r.U, r.T);
      if (r.min_dihedral_deg < 5.0) {
        last_why = "TetGen -" + sw + " at relative cell size " + std::to_string(h) +
                   ": min dihedral angle " + std::to_string(r.min_dihedral_deg) + " deg < 5";
        continue;
      }
      const long long dist = std::llabs(static_cast<long long>(r.U.rows()) - target);
      if (dist > 3LL * target / 10) {
        last_why = "TetGen -" + sw + " at relative cell size " + std::to_string(h) + ": " +
                   std::to_string(r.U.rows()) + " vertices, not within 30% of the target";
        break;  // other switches add interior points too: try another cell size
      }
      const interp::Embedding emb = interp::embed(r.U, r.T, P);
      r.outside_points = static_cast<int>(emb.outside.size());
      if (r.outside_points != 0) {
        last_why = "TetGen -" + sw + " at relative cell size " + std::to_string(h) + ": " +
                   std::to_string(r.outside_points) + " dense vertices outside";
        continue;
      }
      if (dist < best_dist) {
        r.cell_size = h;
        r.tetgen_switches = sw;
        best = std::move(r);
        best_dist = dist;
      }
      break;
    }
    if (best_dist <= target / 10) break;
  }
  if (best.U.rows() == 0)
    throw Error("no TetGen cage with every dihedral angle >= 5 degrees, every vertex inside "
                    "and within 30% of " + std::to_string(target) + " vertices (last: " + last_why +
                    "); use the voxel mesher");
  best.mesher = Mesher::TetGen;
  return best;
}

}  // namespace

const char* mesher_name(Mesher m) { return kMesherNames.name(m); }

Mesher parse_mesher(const std::string& name) {
  if (const std::optional<Mesher> m = kMesherNames.find(name)) return *m;
  throw Error("mesher: " + kMesherNames.unknown(name));
}

bool is_planar(const Eigen::Ref<const Eigen::MatrixXd>& V) {
  if (V.rows() == 0 || V.cols() != 3 || !V.allFinite()) return false;
  if (V.col(2).maxCoeff() != V.col(2).minCoeff()) return false;
  return (V.leftCols(2).colwise().maxCoeff() - V.leftCols(2).colwise().minCoeff()).maxCoeff() > 0;
}

double min_dihedral_angle_deg(const Eigen::Ref<const Eigen::MatrixXd>& U,
                              const Eigen::Ref<const Eigen::MatrixXi>& T) {
  double best = 180.0;
  const double rad = 180.0 / M_PI;
  for (Eigen::Index e = 0; e < T.rows(); ++e) {
    if (U.cols() == 2) {
      for (int a = 0; a < 3; ++a) {
        const Eigen::Vector2d p = U.row(T(e, a)).transpose();
        const Eigen::Vector2d u = U.row(T(e, (a + 1) % 3)).transpose() - p;
        const Eigen::Vector2d w = U.row(T(e, (a + 2) % 3)).transpose() - p;
        const double c = u.dot(w) / (u.norm() * w.norm());
        best = std::min(best, std::acos(std::clamp(c, -1.0, 1.0)) * rad);
      }
      continue;
    }
    // Dihedral angle at edge (a, b): angle between the two faces containing it.
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        int o[2], m = 0;
        for (int c = 0; c < 4; ++c)
          if (c != a && c != b) o[m++] = c;
        const Eigen::Vector3d pa = U.row(T(e, a)).transpose();
        const Eigen::Vector3d ab = U.row(T(e, b)).transpose() - pa;
        const Eigen::Vector3d ax = ab.normalized();
        Eigen::Vector3d u = U.row(T(e, o[0])).transpose() - pa;
        Eigen::Vector3d w = U.row(T(e, o[1])).transpose() - pa;
        u -= ax * ax.dot(u);
        w -= ax * ax.dot(w);
        const double c = u.dot(w) / (u.norm() * w.norm());
        best = std::min(best, std::acos(std::clamp(c, -1.0, 1.0)) * rad);
      }
  }
  return best;
}

CageResult make_cage(const Eigen::Ref<const Eigen::MatrixXd>& V,
                     const Eigen::Ref<const Eigen::MatrixXi>& F, const CageOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  if (V.rows() == 0 || V.cols() != 3)
    throw Error("V must be n x 3 with n > 0, got " + std::to_string(V.rows()) + " x " +
                    std::to_string(V.cols()));
  for (Eigen::Index i = 0; i < V.rows(); ++i)
    if (!V.row(i).allFinite())
      throw Error("vertex " + std::to_string(i) + " is not finite");
  if (F.rows() > 0 && F.cols() != 3)
    throw Error("F must be t x 3");
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    for (int c = 0; c < 3; ++c)
      if (F(t, c) < 0 || F(t, c) >= V.rows())
        throw Error("face " + std::to_string(t) + " index " + std::to_string(F(t, c)) +
                        " out of range");
  if (options.search_steps < 0 || options.search_steps > 10000)
    throw Error("search_steps out of range [0, 10000]");
  if (options.mesher == Mesher::TetGen && !detail::have_tetgen())
    throw Error("this build has no TetGen (MBI_WITH_TETGEN=OFF): use the voxel mesher");

  const double zspan = V.col(2).maxCoeff() - V.col(2).minCoeff();
  const bool tetgen = options.mesher == Mesher::TetGen;
  const int d = (zspan == 0.0 && !options.force_3d && !tetgen) ? 2 : 3;
  const int min_target = d == 3 ? 8 : 4;
  if (options.target_vertices < min_target || options.target_vertices > 1000000)
    throw Error("target_vertices " + std::to_string(options.target_vertices) +
                    " out of range [" + std::to_string(min_target) + ", 1000000]");

  // Scale-free: the cage is built for the model moved to the centre of its bounding box and
  // scaled by its largest extent L (halves first: no overflow at +-1e308), then mapped back.
  // Models of any size mesh alike; what the offset leaves no precision for is refused.
  const Eigen::RowVector3d lo = V.colwise().minCoeff(), hi = V.colwise().maxCoeff();
  const Eigen::RowVector3d center = 0.5 * lo + 0.5 * hi;
  const Eigen::RowVector3d half = 0.5 * hi - 0.5 * lo;
  const double L = 2.0 * half.maxCoeff();
  auto fmt = [](double x) {
    char b[40];
    std::snprintf(b, sizeof b, "%.6g", x);
    return std::string(b);
  };
  if (!(L > 0))
    throw Error("degenerate model: all " + std::to_string(V.rows()) +
                    " vertices are the same point (" + fmt(V(0, 0)) + ", " + fmt(V(0, 1)) + ", " +
                    fmt(V(0, 2)) + "); a cage needs a model with an extent");
  const double offset = std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff());
  if (L < kMinRelativeExtent * offset)
    throw Error("the model's extent " + fmt(L) + " is below the precision of its "
                    "coordinates at offset " + fmt(offset) + " (at least " +
                    fmt(kMinRelativeExtent) + " of the offset is needed); move it near the origin");
  Eigen::MatrixXd Pn = (V.rowwise() - center) / L;
  if (d == 2) Pn.col(2).setZero();
  CageResult r = make_cage_normalised(Pn.leftCols(d), F, options, d);
  // back to the model's units
  r.U = (r.U * L).rowwise() + center.head(d);
  r.cell_size *= L;
  const interp::Embedding emb = interp::embed(r.U, r.T, V.leftCols(d));
  r.outside_points = static_cast<int>(emb.outside.size());
  if (r.outside_points != 0)
    throw Error(std::to_string(r.outside_points) +
                    " vertices fall outside the cage once it is moved back to the model's offset " +
                    fmt(offset) + " (rounding); move the model near the origin");
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

namespace {

CageResult make_cage_normalised(const Eigen::MatrixXd& P, const Eigen::MatrixXi& Fi,
                                const CageOptions& options, int d) {
  const bool tetgen = options.mesher == Mesher::TetGen;
  const double ext = (P.colwise().maxCoeff() - P.colwise().minCoeff()).maxCoeff();
  const double scale = ext > 0 ? ext : 1.0;
  const int target = options.target_vertices;
  const long long cap = grid_cap(target);
  if (tetgen) return make_cage_tetgen(P, Fi, options);

  const Eigen::VectorXd extent = P.colwise().maxCoeff() - P.colwise().minCoeff();
  struct Tried {
    std::array<double, 3> h;
    int count;
    double aspect;  // largest / smallest cell edge
  };
  std::vector<Tried> tried;
  Grid g;
  auto eval_h = [&](const std::array<double, 3>& h) {
    const int c = voxelise(P, Fi, d, h, g, cap) ? count_vertices(g) : std::numeric_limits<int>::max();
    double mn = h[0], mx = h[0];
    for (int a = 1; a < d; ++a) {
      mn = std::min(mn, h[static_cast<std::size_t>(a)]);
      mx = std::max(mx, h[static_cast<std::size_t>(a)]);
    }
    tried.push_back({h, c, mx / mn});
    return c;
  };
  auto eval = [&](double h) { return eval_h({h, h, h}); };
  int best_count = 0;
  if (!search_cell_size(eval, 1.01 * scale, target, options.search_steps, 1.2, best_count))
    unreachable_target(target, best_count, cap);
  // Coarse grids jump in large steps; cells with slightly different edges per axis (one cell
  // more or less along some axes, aspect ratio <= 1.6) fill the gaps between those steps.
  auto by_distance = [&](const Tried& a, const Tried& b) {
    const long long da = std::llabs(static_cast<long long>(a.count) - target);
    const long long db = std::llabs(static_cast<long long>(b.count) - target);
    if (da != db) return da < db;
    return a.h[0] > b.h[0];
  };
  std::stable_sort(tried.begin(), tried.end(), by_distance);
  std::vector<std::array<double, 3>> bases;  // closest isotropic grids below and above target
  for (bool above : {false, true})
    for (const Tried& t : tried)
      if ((t.count >= target) == above && t.count != std::numeric_limits<int>::max()) {
        bases.push_back(t.h);
        break;
      }
  for (const auto& h0 : bases) {
    const int combos = d == 3 ? 27 : 9;
    for (int m = 0; m < combos; ++m) {
      std::array<double, 3> h = h0;
      int code = m;
      bool ok = true;
      for (int a = 0; a < d; ++a, code /= 3) {
        const double ext_a = extent(a);
        const auto ua = static_cast<std::size_t>(a);
        if (ext_a <= 0) continue;
        // n cells along axis a need h in (ext / n, ext / (n - 1)]; take the value in that
        // interval closest to h0, kept 10% away from its lower end (margin around the shape).
        const double n = std::floor(ext_a / h0[ua]) + 1.0 + (code % 3 - 1);
        if (n < 1) {
          ok = false;
          continue;
        }
        const double lo = ext_a / n;
        const double hi = n > 1 ? ext_a / (n - 1) : 4.0 * ext_a;
        h[ua] = std::clamp(h0[ua], lo + 0.1 * (hi - lo), hi);
      }
      if (!ok || h == h0) continue;
      double mn = h[0], mx = h[0];
      for (int a = 1; a < d; ++a) {
        mn = std::min(mn, h[static_cast<std::size_t>(a)]);
        mx = std::max(mx, h[static_cast<std::size_t>(a)]);
      }
      if (mx / mn <= 1.6) eval_h(h);
    }
  }
  // Best: among counts within 10% of the target the most isotropic cells, else the closest count.
  std::stable_sort(tried.begin(), tried.end(), [&](const Tried& a, const Tried& b) {
    const bool na = std::llabs(static_cast<long long>(a.count) - target) <= target / 10;
    const bool nb = std::llabs(static_cast<long long>(b.count) - target) <= target / 10;
    if (na != nb) return na;
    if (na && a.aspect != b.aspect) return a.aspect < b.aspect;
    return by_distance(a, b);
  });

  CageResult res;
  for (std::size_t k = 0; k < tried.size() && k < 8; ++k) {
    if (!voxelise(P, Fi, d, tried[k].h, g, cap)) continue;
    build_mesh(g, res.U, res.T);
    res.cell_size = *std::max_element(tried[k].h.begin(), tried[k].h.begin() + d);
    const interp::Embedding emb = interp::embed(res.U, res.T, P);
    res.outside_points = static_cast<int>(emb.outside.size());
    if (res.outside_points == 0) break;
  }
  if (res.U.rows() == 0 || res.outside_points != 0)
    throw Error("no cell size found whose cage contains every vertex (" +
                    std::to_string(res.outside_points) + " outside)");
  res.min_dihedral_deg = min_dihedral_angle_deg(res.U, res.T);
  return res;
}

}  // namespace

}  // namespace mbi::generate
