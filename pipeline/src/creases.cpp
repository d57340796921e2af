// The creases in colour: per-face gradient jumps carried to the dense points (creases.hpp).
#include <mbi/pipeline/creases.hpp>

#include <mbi/interp/mesh.hpp>
#include <mbi/interp/metrics.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace mbi::pipeline {

Creases::Creases(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T) : U_(U), T_(T) {
  const int d = static_cast<int>(U.cols());
  const Eigen::MatrixXi F = interp::interior_faces(T);
  area_.resize(F.rows());
  opposite_ = Eigen::MatrixXi::Constant(T.rows(), T.cols(), -1);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    Eigen::Vector3d p[3];
    for (int v = 0; v < 3; ++v) p[v].setZero();
    for (int v = 0; v < d; ++v) p[v].head(d) = U.row(F(f, v)).transpose();
    area_(f) = d == 2 ? (p[1] - p[0]).norm() : 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).norm();
    for (int s = 0; s < 2; ++s) {
      const int e = F(f, d + s);
      for (int k = 0; k <= d; ++k)  // the element's vertex not on the face
        if ((F.row(f).head(d).array() != T(e, k)).all()) opposite_(e, k) = static_cast<int>(f);
    }
  }
}

std::vector<bool> Creases::near_faces(const interp::Embedding& emb) const {
  std::vector<bool> near(static_cast<size_t>(emb.size()), false);
  for (int q = 0; q < emb.size(); ++q)
    for (Eigen::Index k = 0; k < opposite_.cols(); ++k)
      if (opposite_(emb.element(q), k) >= 0 && emb.bary(q, k) < kCreaseBand) near[static_cast<size_t>(q)] = true;
  return near;
}

Eigen::VectorXd Creases::face_jumps(const Eigen::Ref<const Eigen::MatrixXd>& X,
                                    const interp::VertexMatrices& M) const {
  const Eigen::VectorXd E = interp::face_discontinuity(U_, T_, X, M);
  Eigen::VectorXd j(E.size());
  for (Eigen::Index f = 0; f < E.size(); ++f) j(f) = area_(f) > 0 ? std::sqrt(std::max(E(f), 0.0) / area_(f)) : 0.0;
  return j;
}

Eigen::VectorXd Creases::face_jumps(FramePipeline& pipe, Method method) const {
  const Eigen::MatrixXd& X = pipe.control_positions();
  if (method == Method::ModifiedBI) return face_jumps(X, pipe.modified_bi_M());
  if (method == Method::Phong) return face_jumps(X, pipe.phong_M());
  const interp::VertexMatrices zero = interp::VertexMatrices::Zero(X.size(), X.cols());  // BI
  return face_jumps(X, zero);
}

Eigen::VectorXd Creases::point_values(const interp::Embedding& emb, const Eigen::Ref<const Eigen::VectorXd>& jumps) const {
  Eigen::VectorXd v = Eigen::VectorXd::Zero(emb.size());
  for (int q = 0; q < emb.size(); ++q)
    for (Eigen::Index k = 0; k < opposite_.cols(); ++k) {
      const int f = opposite_(emb.element(q), k);
      if (f < 0) continue;
      const double w = std::clamp(1.0 - emb.bary(q, k) / kCreaseBand, 0.0, 1.0);
      v(q) = std::max(v(q), w * jumps(f));
    }
  return v;
}

Eigen::Vector3d crease_color(double t) {
  static const Eigen::Vector3d stops[3] = {{0.42, 0.52, 0.78}, {0.92, 0.58, 0.30}, {0.95, 0.18, 0.06}};
  t = std::clamp(std::isfinite(t) ? t : 1.0, 0.0, 1.0);
  const double s = t < 0.5 ? 2 * t : 2 * t - 1;
  const Eigen::Vector3d& a = stops[t < 0.5 ? 0 : 1];
  const Eigen::Vector3d& b = stops[t < 0.5 ? 1 : 2];
  return (1 - s) * a + s * b;
}

double crease_scale(double largest) { return std::isfinite(largest) ? std::max(largest, kCreaseFloor) : kCreaseFloor; }

std::string crease_number(double v) {
  if (v == 0) return "0";
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

}  // namespace mbi::pipeline
