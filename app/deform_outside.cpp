#include "deform_outside.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <vector>

namespace mbi::cli {

double outside_distance(const interp::Embedding& emb, const Eigen::MatrixXd& U, const Eigen::MatrixXi& T,
                        const Eigen::MatrixXd& P, int p) {
  const int d = static_cast<int>(U.cols()), e = emb.element(p);
  const Eigen::VectorXd x = P.row(p).leftCols(d).transpose();
  // The nearest point lies inside some face (vertex, edge, triangle, the simplex itself): the
  // projection onto each face's plane that falls inside the face is a candidate; the least wins.
  double best = std::numeric_limits<double>::infinity();
  for (int mask = 1; mask < (1 << (d + 1)); ++mask) {
    std::vector<int> v;
    for (int k = 0; k <= d; ++k)
      if (mask & (1 << k)) v.push_back(T(e, k));
    const Eigen::VectorXd v0 = U.row(v[0]).transpose();
    Eigen::MatrixXd E(d, static_cast<Eigen::Index>(v.size()) - 1);
    for (std::size_t k = 1; k < v.size(); ++k) E.col(static_cast<Eigen::Index>(k) - 1) = U.row(v[k]).transpose() - v0;
    Eigen::VectorXd c = Eigen::VectorXd::Zero(E.cols());
    if (E.cols() > 0) c = (E.transpose() * E).ldlt().solve(E.transpose() * (x - v0));
    if (c.size() > 0 && (c.minCoeff() < -1e-12 || c.sum() > 1 + 1e-12)) continue;
    const Eigen::VectorXd nearest = v0 + E * c;
    best = std::min(best, (nearest - x).norm());
  }
  return best;
}

void refuse_far_points(const interp::Embedding& emb, const Eigen::MatrixXd& U, const Eigen::MatrixXi& T,
                       const Eigen::MatrixXd& P, double tolerance, const std::string& mesh_name,
                       const std::string& control_name) {
  const double size = (P.colwise().maxCoeff() - P.colwise().minCoeff()).norm();
  const double limit = tolerance * size;
  int far = 0, worst = -1;
  double worst_distance = 0;
  for (int p : emb.outside) {
    const double dist = outside_distance(emb, U, T, P, p);
    if (dist <= limit) continue;
    ++far;
    if (dist > worst_distance) worst_distance = dist, worst = p;
  }
  if (far == 0) return;
  char msg[512];
  std::snprintf(msg, sizeof msg,
                "%d of %d points lie farther outside the control mesh %s than --max-outside %g x the model "
                "size %.4g (%.4g); the worst, point %d, by %.4g (%.3g x the model size)",
                far, emb.size(), control_name.c_str(), tolerance, size, limit, worst, worst_distance,
                size > 0 ? worst_distance / size : 0.0);
  throw std::runtime_error(mesh_name + ": " + msg);
}

}  // namespace mbi::cli
