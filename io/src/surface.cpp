// The steps every surface format shares (surface.hpp).
#include "surface.hpp"

#include <Eigen/Dense>

#include <algorithm>

namespace mbi::io::detail {

Polygons faces_of(const SurfaceMesh& m, const Eigen::Ref<const Eigen::MatrixXd>& V,
                  const std::filesystem::path& file, bool triangles) {
  if (V.cols() != 3) fail(file, 0, "V must be n x 3, got n x " + std::to_string(V.cols()));
  check_finite(V, file, "vertex");
  Polygons faces;
  if (!m.polygons.empty() && !triangles) {
    faces = m.polygons;
  } else {
    if (m.F.cols() != 3 && m.F.rows() > 0) fail(file, 0, "F must be t x 3");
    for (Eigen::Index i = 0; i < m.F.rows(); ++i) faces.push_back({m.F(i, 0), m.F(i, 1), m.F(i, 2)});
  }
  for (std::size_t i = 0; i < faces.size(); ++i) {
    if (faces[i].size() < 3) fail(file, 0, "face " + std::to_string(i) + ": fewer than 3 vertices");
    for (int x : faces[i])
      if (x < 0 || x >= V.rows())
        fail(file, 0, "face " + std::to_string(i) + ": index " + std::to_string(x) +
                          " out of range [0, " + std::to_string(V.rows()) + ")");
  }
  return faces;
}

void set_vertices(SurfaceMesh& m, const std::vector<std::array<double, 3>>& v) {
  m.V.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int c = 0; c < 3; ++c) m.V(static_cast<Eigen::Index>(i), c) = v[i][c];
}

void fan(SurfaceMesh& m) {
  long long t = 0;
  for (const auto& p : m.polygons) t += static_cast<long long>(p.size()) - 2;
  m.F.resize(static_cast<Eigen::Index>(t), 3);
  Eigen::Index r = 0;
  for (const auto& p : m.polygons)
    for (std::size_t k = 1; k + 1 < p.size(); ++k) {
      m.F(r, 0) = p[0];
      m.F(r, 1) = p[k];
      m.F(r, 2) = p[k + 1];
      ++r;
    }
}

namespace {
// v / |v| computed without overflow (v scaled by its largest component first); false when v
// is zero or not finite.
bool unit_vector(Eigen::RowVector3d& v) {
  if (!v.allFinite()) return false;  // maxCoeff is undefined with a NaN
  const double s = v.cwiseAbs().maxCoeff();
  if (!(s > 0)) return false;
  v /= s;
  v /= v.norm();
  return v.allFinite();
}
}  // namespace

// Far-out coordinates (up to the readers' 1e300) overflow the area weights: such a vertex gets
// the sum of its faces' unit normals instead, so the normals are always finite.
void complete_normals(const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Ref<const Eigen::MatrixXi>& F,
                      Eigen::MatrixXd& N, const std::vector<char>& have) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(V.rows(), 3), U = A;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    // edges from halves: no overflow for coordinates below the largest double / 2
    const Eigen::RowVector3d a = 0.5 * V.row(F(f, 0)), e1 = 0.5 * V.row(F(f, 1)) - a,
                             e2 = 0.5 * V.row(F(f, 2)) - a;
    const Eigen::RowVector3d n = 4.0 * e1.cross(e2);
    const double s = std::max(e1.cwiseAbs().maxCoeff(), e2.cwiseAbs().maxCoeff());
    Eigen::RowVector3d u = s > 0 ? Eigen::RowVector3d((e1 / s).cross(e2 / s)) : Eigen::RowVector3d::Zero();
    if (!unit_vector(u)) u.setZero();
    for (int k = 0; k < 3; ++k) {
      A.row(F(f, k)) += n;
      U.row(F(f, k)) += u;
    }
  }
  for (Eigen::Index i = 0; i < N.rows(); ++i) {
    Eigen::RowVector3d n = N.row(i);
    if (static_cast<std::size_t>(i) < have.size() && have[static_cast<std::size_t>(i)] && unit_vector(n)) {
      N.row(i) = n;
      continue;
    }
    n = A.row(i);
    if (!unit_vector(n)) {
      n = U.row(i);
      if (!unit_vector(n)) n << 0, 0, 1;
    }
    N.row(i) = n;
  }
}

void complete_normals(SurfaceMesh& m, const std::vector<char>& have) { complete_normals(m.V, m.F, m.N, have); }


void put_vertex_lines(std::FILE* f, const SurfaceOutput& out, bool with_normals) {
  const auto& V = out.V;
  const auto& N = out.N;
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    std::string l = fmt(V(i, 0)) + " " + fmt(V(i, 1)) + " " + fmt(V(i, 2));
    if (with_normals) l += " " + fmt(N(i, 0)) + " " + fmt(N(i, 1)) + " " + fmt(N(i, 2));
    put(f, l + "\n", out.file);
  }
}

void put_counted_faces(std::FILE* f, const SurfaceOutput& out) {
  for (const auto& p : out.faces) {
    std::string s = std::to_string(p.size());
    for (int x : p) s += " " + std::to_string(x);
    put(f, s + "\n", out.file);
  }
}

}  // namespace mbi::io::detail

namespace mbi::io {

Eigen::MatrixXd vertex_normals(const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Ref<const Eigen::MatrixXi>& F) {
  Eigen::MatrixXd N(V.rows(), 3);
  detail::complete_normals(V, F, N, {});
  return N;
}

}  // namespace mbi::io
