#include <mbi/error.hpp>
#include <mbi/pipeline/contact_setup.hpp>

#include <cmath>
#include <string>

namespace mbi::pipeline {

double default_contact_stiffness(double mass, const Eigen::Vector3d& gravity, double diagonal) {
  if (!(mass > 0) || !std::isfinite(mass)) throw Error("contact stiffness: the mass must be > 0 kg");
  if (!(diagonal > 0) || !std::isfinite(diagonal))
    throw Error("contact stiffness: the model's diagonal must be > 0 m");
  const double g = gravity.norm() > 0 ? gravity.norm() : 9.81;
  return 1e4 * mass * g / diagonal;
}

namespace {
double diagonal_of(const Eigen::Ref<const Eigen::MatrixXd>& P) {
  return P.rows() == 0 ? 0.0 : (P.colwise().maxCoeff() - P.colwise().minCoeff()).norm();
}
}  // namespace

std::shared_ptr<SurfaceContact> make_surface_contact(const Eigen::Ref<const Eigen::MatrixXd>& U,
                                                     const Eigen::Ref<const Eigen::MatrixXi>& T,
                                                     const Eigen::Ref<const Eigen::MatrixXd>& P,
                                                     const PipelineOptions& pipeline,
                                                     const SurfaceContactOptions& options, double mass,
                                                     const Eigen::Vector3d& gravity) {
  if (P.cols() != 3) throw Error("surface contact needs 3D points, got " + std::to_string(P.cols()) + " columns");
  Eigen::MatrixXd points;
  if (options.points.empty()) {
    points = P;
  } else {
    points.resize(static_cast<Eigen::Index>(options.points.size()), 3);
    for (size_t k = 0; k < options.points.size(); ++k) {
      const int i = options.points[k];
      if (i < 0 || i >= P.rows())
        throw Error("contact point " + std::to_string(i) + " out of range (" + std::to_string(P.rows()) + " points)");
      points.row(static_cast<Eigen::Index>(k)) = P.row(i);
    }
  }
  const double k = options.stiffness ? *options.stiffness : default_contact_stiffness(mass, gravity, diagonal_of(P));
  DeformerOptions d;
  d.method = pipeline.method;
  d.interp = pipeline.interp;
  auto deformer = std::make_shared<const Deformer>(U, T, points, d);
  auto contact = std::make_shared<SurfaceContact>(std::move(deformer), options.colliders, k);
  if (options.max_depth) contact->set_max_depth(*options.max_depth);
  if (options.friction_velocity) contact->set_friction_velocity(*options.friction_velocity);
  return contact;
}

int touching_points(const SurfaceContact& contact, const Eigen::Ref<const Eigen::MatrixXd>& X) {
  const Eigen::MatrixXd Xt = X.transpose();  // node-major, as the simulator stacks x
  const Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(Xt.data(), Xt.size());
  return contact.touching(x);
}

}  // namespace mbi::pipeline
