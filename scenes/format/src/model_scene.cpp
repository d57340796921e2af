#include <mbi/scenes/model_scene.hpp>

#include <algorithm>
#include <cmath>

namespace mbi::scenes {

std::optional<DenseBuiltin> builtin_model(const std::filesystem::path& arg) {
  std::error_code ec;
  if (arg.has_extension() || std::filesystem::exists(arg, ec)) return std::nullopt;
  const std::optional<DenseBuiltin> b = kDenseBuiltinNames.find(arg.string());
  if (b == DenseBuiltin::ImageGrid) return std::nullopt;  // a 2D picture grid, not a model
  return b;
}

Scene model_scene(const std::filesystem::path& model) {
  Scene s = surface_scene(model);
  s.name = model.filename().string();
  if (const std::optional<DenseBuiltin> b = builtin_model(model)) s.dense.builtin = *b;
  else s.dense.path = std::filesystem::absolute(model);
  return s;
}

Scene surface_scene(const std::filesystem::path& name) {
  Scene s;
  s.file = name;
  s.name = name.string();
  s.control.generate_vertices = 150;
  s.simulation.parameters.substeps = 2;
  s.simulation.parameters.mass_damping = 1.0;
  s.simulation.parameters.stiffness_damping = 0.02;
  s.simulation.frames = 1 << 30;  // the viewer runs until closed
  s.interpolation.method = pipeline::Method::ModifiedBI;
  s.output.up = Eigen::Vector3d::UnitY();
  return s;
}

void fit_to_model(Scene& scene, const Eigen::Ref<const Eigen::MatrixXd>& V) {
  const Eigen::Vector3d lo = V.colwise().minCoeff().transpose(), hi = V.colwise().maxCoeff().transpose();
  const Eigen::Vector3d extent = hi - lo;
  const double size = std::max(extent.norm(), 1e-9);
  constexpr double kCrossing = 1.3;  // s, for a wave to cross the model
  scene.material.density = 1000;
  scene.material.poisson_ratio = 0.4;
  scene.material.youngs_modulus = scene.material.density * std::pow(size / kCrossing, 2);
  // held at the bottom; a model flat in y (a sheet lying down) by one end of its longest axis,
  // since its bottom tenth would be all of it
  Eigen::Index axis = 1;
  if (extent.y() < 0.1 * size) extent.maxCoeff(&axis);
  ConstraintSpec held;
  Eigen::Vector3d box_hi = Eigen::Vector3d::Ones();
  box_hi(axis) = 0.1;
  held.select.box_relative = std::make_pair(Eigen::Vector3d::Zero(), box_hi);
  held.select.where = scene.file.string();
  scene.constraints = {held};
}

}  // namespace mbi::scenes
