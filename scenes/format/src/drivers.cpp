// make_driver and make_pipeline: what moves a scene's control mesh (the simulator with its
// constraints and pokes, or the dragged handles) and the frame pipeline around it.
#include <mbi/interp.hpp>
#include <mbi/io/io.hpp>
#include <mbi/scenes/models.hpp>
#include <mbi/sim/simulator.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <memory>

namespace mbi::scenes {
namespace {

void check_mode(const Scene& sc, const SceneModels& m) {
  if (sc.mode == Mode::Simulate && m.dim() != 3)
    throw Error(sc.file.string() + ": mode = \"" + mode_name(Mode::Simulate) +
                     "\" needs a 3D control mesh (use mode = \"" + mode_name(Mode::Drag) + "\" in 2D)");
}

// Linear interpolation of drag keyframes at frame f (held before the first and after the last).
Eigen::Vector3d key_at(const DragSpec& d, double f) {
  if (f <= d.keys.front().first) return d.keys.front().second;
  if (f >= d.keys.back().first) return d.keys.back().second;
  for (size_t k = 0; k + 1 < d.keys.size(); ++k)
    if (f <= d.keys[k + 1].first) {
      const double s = (f - d.keys[k].first) / (d.keys[k + 1].first - d.keys[k].first);
      return (1 - s) * d.keys[k].second + s * d.keys[k + 1].second;
    }
  return d.keys.back().second;
}

void add_constraints(const Scene& sc, const Eigen::MatrixXd& U, sim::Simulator& simulator) {
  for (const ConstraintSpec& c : sc.constraints) {
    const std::vector<int> nodes = select_nodes(c.select, U);
    if (c.kind == ConstraintSpec::Kind::Fixed)
      simulator.fix(nodes);
    else
      simulator.add_kinematic(nodes, c.motion);
  }
}

// A poke's material point: `point` itself, or for `at` the dense vertex nearest to a point given
// in fractions of the dense model's bounding box.
Eigen::MatrixXd poke_point(const PokeSpec& ps, const SceneModels& m) {
  Eigen::MatrixXd q = ps.point.transpose();
  if (ps.relative) {
    const Eigen::RowVector3d lo = m.dense.V.colwise().minCoeff(), hi = m.dense.V.colwise().maxCoeff();
    const Eigen::RowVector3d want = lo + ps.point.transpose().cwiseProduct(hi - lo);
    Eigen::Index best = 0;
    (m.dense.V.rowwise() - want).rowwise().squaredNorm().minCoeff(&best);
    q = m.dense.V.row(best);
  }
  return q;
}

void add_pokes(const Scene& sc, const SceneModels& m, pipeline::SimulatorDriver& driver) {
  for (const PokeSpec& ps : sc.pokes) {
    const Eigen::MatrixXd q = poke_point(ps, m);
    const std::string point = "pokes: point (" + format_num(ps.point.x()) + ", " +
                              format_num(ps.point.y()) + ", " + format_num(ps.point.z()) + ")";
    interp::Embedding e;
    try {
      e = interp::embed(m.U, m.T, q);
    } catch (const interp::Error& err) {
      throw Error(sc.file.string() + ": " + point + ": " + err.what());
    }
    if (!e.outside.empty())
      throw Error(sc.file.string() + ": " + point + " is outside the control mesh");
    const Eigen::Vector4d bary = e.bary.row(0).transpose();
    if (ps.force) {
      driver.add_scripted_force(ps.first, ps.last, e.element(0), bary, *ps.force);
    } else {
      const double size = ps.offset_in_sizes ? (m.dense.V.colwise().maxCoeff() - m.dense.V.colwise().minCoeff()).norm()
                                             : 1.0;
      const Eigen::Vector3d target = ps.target_relative ? Eigen::Vector3d(size * *ps.target + q.row(0).transpose())
                                                        : *ps.target;
      driver.add_scripted_spring(ps.first, ps.last, e.element(0), bary, target, ps.stiffness);
    }
  }
}

double diagonal(const Eigen::MatrixXd& V) {
  return V.rows() == 0 ? 0.0 : (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
}

// The dense vertices that touch: simulation.contact_select, or all (an empty list).
std::vector<int> contact_points(const Scene& sc, const SceneModels& m) {
  if (!sc.simulation.contact_select) return {};
  try {
    return select_nodes(*sc.simulation.contact_select, m.dense.V);
  } catch (const Error& e) {  // select_nodes speaks of control nodes; this selects dense vertices
    std::string what = e.what();
    for (const auto& [from, to] : {std::pair<std::string, std::string>{": select", ": simulation.contact_select"},
                                   {"control node", "dense vertex"}, {"control mesh", "dense model"}})
      if (const auto at = what.find(from); at != std::string::npos) what.replace(at, from.size(), to);
    throw Error(what);
  }
}

// contact = surface: the dense surface's vertices touch the colliders, evaluated with the
// scene's method, as the simulator's potential.
void add_surface_contact(const Scene& sc, const SceneModels& m, pipeline::SimulatorDriver& driver) {
  pipeline::PipelineOptions po;
  po.method = sc.interpolation.method;
  po.interp = sc.interpolation.options;
  pipeline::SurfaceContactOptions o;
  o.colliders = sc.colliders;
  for (const ColliderMesh& mesh : sc.collider_meshes)  // a scene of parse_scene alone: read now
    if (!o.colliders.at(mesh.index).level_set) o.colliders[mesh.index].level_set = read_collider_mesh(sc, mesh);
  o.stiffness = sc.simulation.contact_stiffness;
  o.max_depth = sc.simulation.contact_max_depth;
  o.friction_velocity = sc.simulation.contact_friction_velocity;
  o.points = contact_points(sc, m);
  const sim::Simulator& s = driver.simulator();
  try {
    driver.set_contact(pipeline::make_surface_contact(m.U, m.T, m.dense.V, po, o, s.masses().sum(), s.params().gravity));
  } catch (const mbi::Error& e) {  // a collider overlapping the model at rest, named by its index
    throw Error(sc.file.string() + ": simulation.contact: " + e.what() +
                " (colliders are numbered as the [[colliders]] entries, then the ground)");
  }
}

sim::Parameters simulation_parameters(const Scene& sc, const SceneModels& m) {
  sim::Parameters p = sc.simulation.parameters;
  const bool surface = sc.simulation.contact == pipeline::ContactMode::Surface;
  if (sc.simulation.newton_tolerance)
    p.newton_tolerance = *sc.simulation.newton_tolerance;
  else if (surface)
    p.newton_tolerance = surface_newton_tolerance(diagonal(m.dense.V), p.dt / p.substeps);
  return p;
}

std::unique_ptr<pipeline::Driver> simulation_driver(const Scene& sc, const SceneModels& m) {
  const sim::Material& mat = sc.material;
  sim::Simulator simulator(m.U, m.T, mat, simulation_parameters(sc, m));
  add_constraints(sc, m.U, simulator);
  auto driver = std::make_unique<pipeline::SimulatorDriver>(std::move(simulator));
  add_pokes(sc, m, *driver);
  if (sc.simulation.contact == pipeline::ContactMode::Surface) add_surface_contact(sc, m, *driver);
  return driver;
}

// The dragged control vertices (handles) and, for each, the [[drags]] entry that moves it.
void drag_handles(const Scene& sc, const SceneModels& m, std::vector<int>& vertices,
                  std::vector<int>& drag_of) {
  for (size_t k = 0; k < sc.drags.size(); ++k) {
    const DragSpec& dr = sc.drags[k];
    std::vector<int> vs;
    if (dr.select) {
      vs = select_nodes(*dr.select, m.U);
    } else if (dr.near) {
      Eigen::Index v = 0;
      (m.U.rowwise() - dr.near->head(m.dim()).transpose()).rowwise().squaredNorm().minCoeff(&v);
      vs.push_back(static_cast<int>(v));
    } else {
      vs.push_back(dr.vertex);
    }
    const std::string where = sc.file.string() + ": drags[" + std::to_string(k) + "]: ";
    for (int v : vs) {
      if (v >= m.U.rows())
        throw Error(where + "vertex " + std::to_string(v) + " out of range (control mesh has " +
                         std::to_string(m.U.rows()) + ")");
      if (std::find(vertices.begin(), vertices.end(), v) != vertices.end())
        throw Error(where + "control vertex " + std::to_string(v) + " is dragged twice");
      vertices.push_back(v);
      drag_of.push_back(static_cast<int>(k));
    }
  }
}

std::unique_ptr<pipeline::Driver> drag_driver(const Scene& sc, const SceneModels& m) {
  const int d = m.dim();
  std::vector<int> vertices, drag_of;
  drag_handles(sc, m, vertices, drag_of);
  interp::ControlOptions co;
  co.interp = sc.interpolation.options;
  co.mode = sc.interpolation.handles;
  const Eigen::MatrixXd U = m.U;
  auto targets = [U, vertices, drag_of, drags = sc.drags, d](int f) {
    Eigen::MatrixXd t(static_cast<Eigen::Index>(vertices.size()), d);
    for (size_t k = 0; k < vertices.size(); ++k)
      t.row(static_cast<Eigen::Index>(k)) =
          U.row(vertices[k]) + key_at(drags[static_cast<size_t>(drag_of[k])], f).head(d).transpose();
    return t;
  };
  return std::make_unique<pipeline::HandleDriver>(m.U, m.T, vertices, co, targets);
}

}  // namespace

std::unique_ptr<pipeline::Driver> make_driver(const Scene& sc, const SceneModels& m) {
  check_mode(sc, m);
  return sc.mode == Mode::Simulate ? simulation_driver(sc, m) : drag_driver(sc, m);
}

pipeline::FramePipeline make_pipeline(const Scene& sc, const SceneModels& m,
                                      interp::Embedding embedding,
                                      std::unique_ptr<pipeline::Evaluator> evaluator) {
  pipeline::PipelineOptions po;
  po.method = sc.interpolation.method;
  po.interp = sc.interpolation.options;
  auto driver = make_driver(sc, m);
  // rest normals of a 3D surface: evaluated normals for the GPU's pictures and the viewer; a
  // model with normals of its own has them evaluated every frame (written with the meshes)
  const bool file_normals = m.dim() == 3 && m.dense.N.rows() == m.dense.V.rows() && m.dense.N.cols() == 3;
  po.normals = file_normals;
  const Eigen::MatrixXd normals = file_normals ? m.dense.N
                                  : m.dim() == 3 && m.dense.F.rows() > 0 ? io::vertex_normals(m.dense.V, m.dense.F)
                                                                         : Eigen::MatrixXd();
  return pipeline::FramePipeline(m.U, m.T, std::move(embedding), std::move(driver), po,
                                 std::move(evaluator), normals);
}

}  // namespace mbi::scenes
