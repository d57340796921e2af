// Control-mesh validation and topology (one code path for triangles and tetrahedra).
#include <mbi/interp/mesh.hpp>

#include "method/detail.hpp"

#include <array>
#include <cmath>
#include <vector>

namespace mbi::interp {
namespace detail {

void check_shapes(const Eigen::Ref<const Eigen::MatrixXd>& U,
                  const Eigen::Ref<const Eigen::MatrixXi>& T) {
  const auto d = U.cols();
  if (d != 2 && d != 3)
    throw Error("rest positions must be n x 2 or n x 3, got " +
                std::to_string(U.rows()) + " x " + std::to_string(d));
  if (T.cols() != d + 1)
    throw Error("elements must be m x " + std::to_string(d + 1) +
                " for d = " + std::to_string(d) + ", got m x " + std::to_string(T.cols()));
  if (T.rows() == 0) throw Error("the control mesh has no elements");
  const auto n = U.rows();
  for (Eigen::Index e = 0; e < T.rows(); ++e)
    for (Eigen::Index k = 0; k < T.cols(); ++k)
      if (T(e, k) < 0 || T(e, k) >= n)
        throw Error("element " + std::to_string(e) + " has vertex index " +
                    std::to_string(T(e, k)) + " outside [0, " + std::to_string(n) + ")");
}

void check_finite(const char* what, const Eigen::Ref<const Eigen::MatrixXd>& A) {
  for (Eigen::Index i = 0; i < A.rows(); ++i)
    for (Eigen::Index c = 0; c < A.cols(); ++c)
      if (!std::isfinite(A(i, c)))
        throw Error(std::string(what) + " " + std::to_string(i) +
                    " has a non-finite coordinate (column " + std::to_string(c) + ")");
}

void check_point_list(const Embedding& emb, std::span<const Eigen::Index> points, long long elements) {
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Index p = points[i];
    if (p < 0 || p >= emb.size())
      throw Error("points[" + std::to_string(i) + "] = " + std::to_string(p) + " is outside [0, " +
                  std::to_string(emb.size()) + ")");
    if (emb.element(p) < 0 || emb.element(p) >= elements)
      throw Error("point " + std::to_string(p) + " refers to element " + std::to_string(emb.element(p)) +
                  " outside [0, " + std::to_string(elements) + ")");
  }
}

void check_index_list(const char* what, std::span<const int> list, long long count) {
  for (size_t i = 0; i < list.size(); ++i)
    if (list[i] < 0 || list[i] >= count)
      throw Error(std::string(what) + "[" + std::to_string(i) + "] = " + std::to_string(list[i]) + " is outside [0, " +
                  std::to_string(count) + ")");
}

}  // namespace detail

namespace {

// Edge matrix [u_1 - u_0, ..., u_d - u_0] (d x d) of element e.
Eigen::MatrixXd edge_matrix(const Eigen::Ref<const Eigen::MatrixXd>& U,
                            const Eigen::Ref<const Eigen::MatrixXi>& T, Eigen::Index e) {
  const auto d = U.cols();
  Eigen::MatrixXd E(d, d);
  for (Eigen::Index k = 0; k < d; ++k) E.col(k) = (U.row(T(e, k + 1)) - U.row(T(e, 0))).transpose();
  return E;
}

double factorial(int d) { return d == 2 ? 2.0 : 6.0; }

using FaceKey = std::array<int, 3>;  // sorted vertex indices; unused slots -1 (2D)

struct FaceRecord {
  FaceKey key;
  int element;
  int local;  // local index of the opposite vertex
  bool operator<(const FaceRecord& o) const {
    return key != o.key ? key < o.key : element < o.element;
  }
};

std::vector<FaceRecord> sorted_faces(const Eigen::Ref<const Eigen::MatrixXi>& T) {
  const int nv = static_cast<int>(T.cols());
  std::vector<FaceRecord> faces;
  faces.reserve(static_cast<size_t>(T.rows()) * nv);
  for (int e = 0; e < T.rows(); ++e)
    for (int k = 0; k < nv; ++k) {
      FaceKey key{-1, -1, -1};
      int j = 0;
      for (int l = 0; l < nv; ++l)
        if (l != k) key[j++] = T(e, l);
      // sort the d used slots (tiny insertion sort; std::sort trips -Warray-bounds in GCC 12)
      for (int a = 1; a < nv - 1; ++a)
        for (int b = a; b > 0 && key[b - 1] > key[b]; --b) std::swap(key[b - 1], key[b]);
      faces.push_back({key, e, k});
    }
  std::sort(faces.begin(), faces.end());
  return faces;
}

std::string face_name(const FaceKey& key, int d) {
  std::string s = "(";
  for (int j = 0; j < d; ++j) s += (j ? ", " : "") + std::to_string(key[j]);
  return s + ")";
}

}  // namespace

void validate_mesh(const Eigen::Ref<const Eigen::MatrixXd>& U,
                   const Eigen::Ref<const Eigen::MatrixXi>& T, double rel_tol) {
  detail::check_shapes(U, T);
  detail::check_finite("vertex", U);
  if (!(rel_tol >= 0)) throw Error("rel_tol must be >= 0");
  const int d = static_cast<int>(U.cols());
  for (Eigen::Index e = 0; e < T.rows(); ++e) {
    for (int a = 0; a <= d; ++a)
      for (int b = a + 1; b <= d; ++b)
        if (T(e, a) == T(e, b))
          throw Error("element " + std::to_string(e) + " repeats vertex " +
                      std::to_string(T(e, a)));
    double h = 0;
    int edges = 0;
    for (int a = 0; a <= d; ++a)
      for (int b = a + 1; b <= d; ++b, ++edges) h += (U.row(T(e, a)) - U.row(T(e, b))).norm();
    h /= edges;
    const double vol = element_volume(U, T, static_cast<int>(e));
    if (!(std::abs(vol) > rel_tol * std::pow(h, d)))
      throw Error("element " + std::to_string(e) + " is degenerate (volume " +
                  std::to_string(vol) + ", mean edge length " + std::to_string(h) + ")");
  }
}

namespace {
// Checks dimensions and element e's indices only (O(1), unlike check_shapes).
void check_element(const Eigen::Ref<const Eigen::MatrixXd>& U,
                   const Eigen::Ref<const Eigen::MatrixXi>& T, int e) {
  const auto d = U.cols();
  if ((d != 2 && d != 3) || T.cols() != d + 1)
    throw Error("expected U n x d (d = 2, 3) and T m x (d+1), got U " +
                std::to_string(U.rows()) + " x " + std::to_string(d) + ", T " +
                std::to_string(T.rows()) + " x " + std::to_string(T.cols()));
  if (e < 0 || e >= T.rows())
    throw Error("element " + std::to_string(e) + " out of range [0, " +
                std::to_string(T.rows()) + ")");
  for (Eigen::Index k = 0; k <= d; ++k)
    if (T(e, k) < 0 || T(e, k) >= U.rows())
      throw Error("element " + std::to_string(e) + " has vertex index " +
                  std::to_string(T(e, k)) + " outside [0, " + std::to_string(U.rows()) + ")");
}
}  // namespace

double element_volume(const Eigen::Ref<const Eigen::MatrixXd>& U,
                      const Eigen::Ref<const Eigen::MatrixXi>& T, int e) {
  check_element(U, T, e);
  const Eigen::MatrixXd E = edge_matrix(U, T, e);
  return E.determinant() / factorial(static_cast<int>(U.cols()));
}

Eigen::MatrixXi interior_faces(const Eigen::Ref<const Eigen::MatrixXi>& T) {
  const int d = static_cast<int>(T.cols()) - 1;
  if (d != 2 && d != 3) throw Error("elements must have 3 or 4 vertices");
  const auto faces = sorted_faces(T);
  std::vector<std::array<int, 5>> rows;
  for (size_t i = 0; i < faces.size();) {
    size_t j = i;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j - i > 2)
      throw Error("face " + face_name(faces[i].key, d) + " is shared by " +
                  std::to_string(j - i) + " elements (non-manifold), e.g. element " +
                  std::to_string(faces[i].element));
    if (j - i == 2) {
      std::array<int, 5> r{};
      for (int k = 0; k < d; ++k) r[k] = faces[i].key[k];
      r[d] = faces[i].element;
      r[d + 1] = faces[i + 1].element;
      rows.push_back(r);
    }
    i = j;
  }
  Eigen::MatrixXi F(static_cast<Eigen::Index>(rows.size()), d + 2);
  for (size_t i = 0; i < rows.size(); ++i)
    for (int k = 0; k < d + 2; ++k) F(static_cast<Eigen::Index>(i), k) = rows[i][k];
  return F;
}

Eigen::MatrixXi boundary_faces(const Eigen::Ref<const Eigen::MatrixXd>& U,
                               const Eigen::Ref<const Eigen::MatrixXi>& T) {
  detail::check_shapes(U, T);
  const int d = static_cast<int>(U.cols());
  const auto faces = sorted_faces(T);
  std::vector<std::array<int, 3>> rows;
  for (size_t i = 0; i < faces.size();) {
    size_t j = i;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j - i == 1) {
      const FaceRecord& f = faces[i];
      std::array<int, 3> r{-1, -1, -1};
      int c = 0;
      for (int l = 0; l <= d; ++l)
        if (l != f.local) r[c++] = T(f.element, l);
      const Eigen::Vector3d o = [&] {
        Eigen::Vector3d v = Eigen::Vector3d::Zero();
        v.head(d) = U.row(T(f.element, f.local)).transpose();
        return v;
      }();
      auto p = [&](int v) {
        Eigen::Vector3d q = Eigen::Vector3d::Zero();
        q.head(d) = U.row(v).transpose();
        return q;
      };
      Eigen::Vector3d normal;
      if (d == 3) {
        normal = (p(r[1]) - p(r[0])).cross(p(r[2]) - p(r[0]));
      } else {
        const Eigen::Vector3d t = p(r[1]) - p(r[0]);
        normal = Eigen::Vector3d(t.y(), -t.x(), 0.0);
      }
      if (normal.dot(o - p(r[0])) > 0) std::swap(r[0], r[1]);
      rows.push_back(r);
    }
    i = j;
  }
  Eigen::MatrixXi B(static_cast<Eigen::Index>(rows.size()), d);
  for (size_t i = 0; i < rows.size(); ++i)
    for (int k = 0; k < d; ++k) B(static_cast<Eigen::Index>(i), k) = rows[i][k];
  return B;
}

Eigen::VectorXi boundary_vertices(int n, const Eigen::Ref<const Eigen::MatrixXi>& T) {
  const int d = static_cast<int>(T.cols()) - 1;
  if (d != 2 && d != 3) throw Error("elements must have 3 or 4 vertices");
  if (n < 0) throw Error("n must be >= 0");
  for (Eigen::Index e = 0; e < T.rows(); ++e)
    for (int k = 0; k <= d; ++k)
      if (T(e, k) < 0 || T(e, k) >= n)
        throw Error("element " + std::to_string(e) + " has vertex index " +
                    std::to_string(T(e, k)) + " outside [0, " + std::to_string(n) + ")");
  Eigen::VectorXi flag = Eigen::VectorXi::Zero(n);
  const auto faces = sorted_faces(T);
  for (size_t i = 0; i < faces.size();) {
    size_t j = i;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j - i == 1)
      for (int k = 0; k < d; ++k) flag(faces[i].key[k]) = 1;
    i = j;
  }
  return flag;
}

Eigen::MatrixXd basis_gradients(const Eigen::Ref<const Eigen::MatrixXd>& U,
                                const Eigen::Ref<const Eigen::MatrixXi>& T, int e) {
  check_element(U, T, e);
  const auto d = U.cols();
  const Eigen::MatrixXd E = edge_matrix(U, T, e);
  Eigen::FullPivLU<Eigen::MatrixXd> lu(E);
  if (!lu.isInvertible())
    throw Error("element " + std::to_string(e) + " is degenerate");
  const Eigen::MatrixXd Einv = lu.inverse();  // row k-1 = a_k^T for k >= 1
  Eigen::MatrixXd A(d + 1, d);
  A.bottomRows(d) = Einv;
  A.row(0) = -Einv.colwise().sum();
  return A;
}

}  // namespace mbi::interp
