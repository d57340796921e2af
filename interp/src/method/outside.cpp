#include <mbi/interp/outside.hpp>

#include <cmath>
#include <cstdio>

namespace mbi::interp {

double check_max_outside(double tolerance) {
  if (!std::isfinite(tolerance) || !(tolerance >= 0))
    throw Error("max_outside must be a finite number >= 0 (x the model size), got " + std::to_string(tolerance));
  return tolerance;
}

FarPoints far_points(const Embedding& emb, const Eigen::Ref<const Eigen::MatrixXd>& P, double tolerance) {
  if (P.rows() != emb.size() || emb.outside_distance.size() != emb.outside.size())
    throw Error("far_points: P has " + std::to_string(P.rows()) + " rows, the embedding " +
                std::to_string(emb.size()) + " points");
  FarPoints far;
  far.points = emb.size();
  far.tolerance = check_max_outside(tolerance);
  if (P.rows() > 0) far.model_size = (P.colwise().maxCoeff() - P.colwise().minCoeff()).norm();
  far.limit = tolerance * far.model_size;
  for (std::size_t k = 0; k < emb.outside.size(); ++k) {
    const double dist = emb.outside_distance[k];
    if (dist <= far.limit) continue;
    ++far.count;
    if (dist > far.worst_distance) far.worst_distance = dist, far.worst = emb.outside[k];
  }
  return far;
}

std::string far_points_message(const FarPoints& far, const std::string& option, const std::string& control) {
  char msg[512];
  std::snprintf(msg, sizeof msg,
                "%d of %d points lie farther outside the control mesh %s than %s%g x the model size %.4g (%.4g); "
                "the worst, point %d, by %.4g (%.3g x the model size)",
                far.count, far.points, control.c_str(), option.c_str(), far.tolerance, far.model_size, far.limit,
                far.worst, far.worst_distance, far.model_size > 0 ? far.worst_distance / far.model_size : 0.0);
  return msg;
}

std::string outside_message(const Embedding& emb) {
  if (emb.outside.empty()) return {};
  char msg[256];
  std::snprintf(msg, sizeof msg,
                "%zu of %d points lie outside the control mesh (farthest %.3g); they follow the nearest element by "
                "extrapolation",
                emb.outside.size(), emb.size(), emb.max_outside_distance);
  return msg;
}

}  // namespace mbi::interp
