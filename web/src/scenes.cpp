// The page's scenes: the settings of scenes/twist-bar.toml and scenes/poke.toml (poke's also for a
// dense generated sphere), built from mbi::generate's shapes and its voxel mesher (the page reads
// no scene file).
#include <mbi/web/page_model.hpp>

#include <mbi/generate/cage.hpp>
#include <mbi/generate/procedural.hpp>

#include <string>

namespace mbi::web {
namespace {

// Nodes whose coordinate c lies in [lo, hi] of the bounding box (fractions; as a scene's
// select.box_relative does).
std::vector<int> nodes_between(const Eigen::MatrixXd& U, int c, double lo, double hi) {
  const double a = U.col(c).minCoeff(), ext = U.col(c).maxCoeff() - a, tol = 1e-9 * (1 + ext);
  std::vector<int> nodes;
  for (Eigen::Index i = 0; i < U.rows(); ++i)
    if (U(i, c) >= a + lo * ext - tol && U(i, c) <= a + hi * ext + tol) nodes.push_back(static_cast<int>(i));
  return nodes;
}

// poke.toml's time stepping and material: soft, damped, no gravity.
sim::Simulator poke_simulator(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T) {
  sim::Parameters p;
  p.dt = 0.0333333333;
  p.substeps = 2;
  p.gravity.setZero();
  p.mass_damping = 1.0;
  p.stiffness_damping = 0.02;
  sim::Simulator s(U, T, {.youngs_modulus = 1e4, .poisson_ratio = 0.4, .density = 1000}, p);
  s.fix(nodes_between(U, 1, 0.0, 0.1));  // the bottom tenth in y
  return s;
}

std::string counts(const Eigen::MatrixXd& V, const Eigen::MatrixXd& U) {
  return std::to_string(V.rows()) + " dense vertices, " + std::to_string(U.rows()) + " control vertices";
}

}  // namespace

PageModel PageModel::builtin(SceneKind kind) {
  Surface dense;
  Eigen::MatrixXd U;
  Eigen::MatrixXi T;
  if (kind == SceneKind::DenseSphere) {  // 252,152 points: the evaluators side by side
    generate::bumpy_sphere(1.0, 205, 0.05, dense.V, dense.F);
    generate::CageResult cage = generate::make_cage(dense.V, dense.F, {.target_vertices = 150});
    sim::Simulator s = poke_simulator(cage.U, cage.T);
    std::string what = "dense sphere: " + counts(dense.V, cage.U);
    return PageModel(cage.U, cage.T, std::move(dense), std::move(s), std::nullopt, std::move(what));
  }
  if (kind == SceneKind::Poke) {
    generate::cylinder_surface(0.5, 4.0, 96, 192, 12, dense.V, dense.F);
    generate::CageResult cage = generate::make_cage(dense.V, dense.F, {.target_vertices = 150});
    sim::Simulator s = poke_simulator(cage.U, cage.T);
    std::string what = "poke: the built-in cylinder, " + counts(dense.V, cage.U);
    return PageModel(cage.U, cage.T, std::move(dense), std::move(s), std::nullopt, std::move(what));
  }
  // twist-bar.toml: one end held, the other twisted by 90 degrees over 3 s, then held
  generate::paper_bar_control(U, T);
  generate::paper_bar_surface(dense.V, dense.F);
  sim::Parameters p;
  p.dt = 0.0333333333;
  p.substeps = 2;
  p.gravity.setZero();
  p.stiffness_damping = 0.01;
  sim::Simulator s(U, T, {.youngs_modulus = 1e6, .poisson_ratio = 0.45, .density = 1000}, p);
  s.fix(nodes_between(U, 2, 0.0, 0.0));
  s.add_kinematic(nodes_between(U, 2, 1.0, 1.0), {.center = Eigen::Vector3d(0, 0, 6),
                                                 .axis = Eigen::Vector3d::UnitZ(),
                                                 .angular_velocity = 0.5235987756,
                                                 .stop = 3.0});
  std::string what = "twisting bar: the paper's bar, " + counts(dense.V, U);
  return PageModel(U, T, std::move(dense), std::move(s), std::nullopt, std::move(what));
}

PageModel PageModel::surface(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, int control_vertices) {
  // a flat model gets a 3D cage too: the simulator is 3D
  generate::CageResult cage =
      generate::make_cage(V, F, {.target_vertices = control_vertices, .force_3d = true});
  sim::Simulator s = poke_simulator(cage.U, cage.T);
  std::string what = "your model: " + counts(V, cage.U);
  return PageModel(cage.U, cage.T, Surface{V, F}, std::move(s), std::nullopt, std::move(what));
}

}  // namespace mbi::web
