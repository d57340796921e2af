// Contact on the pipeline's coupled step: mbi.Collider (pipeline::Collider), a FramePipeline whose
// Simulator steps with contact at the dense points (FramePipeline.with_contact), a scene's
// pipeline as `mbi run` builds it, contact keys included (FramePipeline.from_scene), and the
// contact figures of the last frame (FramePipeline.contact). The Simulator binding stays the raw
// simulator: contact is set up here, at the level where the simulator and the embedding meet.
#include "objects.hpp"

#include <mbi/interp/embed.hpp>
#include <mbi/pipeline/contact_setup.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>
#include <mbi/pipeline/mesh_level_set.hpp>
#include <mbi/scenes/models.hpp>

#include <cmath>
#include <sstream>
#include <tuple>

namespace mbi::python {
namespace {

using pipeline::Collider;
using Object = Guarded<pipeline::FramePipeline>;

// distance() at many points: one array in, two out, the GIL released while they are measured.
py::tuple distances(const Collider& c, const py::object& P, double time) {
  if (!std::isfinite(time)) throw Error("time must be finite, got " + std::to_string(time));
  const Input p = float_matrix(P, "P", {-1, 3});
  Eigen::VectorXd d(p.map.rows());
  Eigen::MatrixXd normals(p.map.rows(), 3);
  {
    py::gil_scoped_release release;
    for (Eigen::Index i = 0; i < p.map.rows(); ++i) {
      const pipeline::Distance di = pipeline::signed_distance(c, p.map.row(i).transpose(), time);
      d(i) = di.value;
      normals.row(i) = di.normal.transpose();
    }
  }
  return py::make_tuple(to_numpy_vector(d), to_numpy(std::move(normals)));
}

// A Simulator that Python holds, stepped once a frame (not for frame 0, the initial pose) with
// surface contact as its potential, as pipeline::SimulatorDriver steps the simulator it owns.
class ContactDriving final : public pipeline::Driver {
 public:
  ContactDriving(std::shared_ptr<SimulatorObject> s, std::shared_ptr<pipeline::SurfaceContact> contact)
      : s_(std::move(s)), contact_(std::move(contact)) {
    std::lock_guard<std::mutex> lock(s_->mutex);
    s_->object.set_potential(contact_);
  }
  pipeline::DriveResult drive(int frame, Eigen::MatrixXd& X) override {
    std::lock_guard<std::mutex> lock(s_->mutex);
    if (frame > 0) {
      last_ = s_->object.step();
      if (!last_.success) return {false, last_.message};
    } else {
      contact_->set_time(s_->object.time());
    }
    X = s_->object.positions();
    touching_ = pipeline::touching_points(*contact_, X);
    return {};
  }
  void reset() override {
    std::lock_guard<std::mutex> lock(s_->mutex);
    s_->object.reset();
    last_ = {};
    touching_ = 0;
  }
  const char* name() const override { return "simulation"; }
  const sim::StepResult& last_step() const { return last_; }
  const pipeline::SurfaceContact& contact() const { return *contact_; }
  int touching_points() const { return touching_; }

 private:
  std::shared_ptr<SimulatorObject> s_;
  std::shared_ptr<pipeline::SurfaceContact> contact_;
  sim::StepResult last_;
  int touching_ = 0;
};

std::unique_ptr<Object> with_contact(const py::object& U, const py::object& T, const py::object& P,
                                     const std::shared_ptr<SimulatorObject>& simulator,
                                     const std::vector<Collider>& colliders, std::optional<double> stiffness,
                                     const py::object& points, const std::string& method, std::optional<double> alpha,
                                     double beta, bool pin_boundary) {
  const Mesh c = control_mesh(U, T);
  const Input p = float_matrix(P, "P", {-1, 3});
  pipeline::PipelineOptions o;
  o.method = pipeline::kMethodNames.parse(method, "method");
  o.interp.alpha = alpha;
  o.interp.beta = beta;
  o.interp.pin_boundary = pin_boundary;
  pipeline::SurfaceContactOptions co;
  co.colliders = colliders;
  co.stiffness = stiffness;
  if (!points.is_none()) co.points = index_list(points, "points", p.map.rows());
  const auto [nodes, mass, gravity] = simulator->run([](const sim::Simulator& s) {
    return std::tuple<int, double, Eigen::Vector3d>(s.nodes(), s.masses().sum(), s.params().gravity);
  });
  if (nodes != c.U.map.rows())
    throw Error("the simulator has " + std::to_string(nodes) + " nodes, U has " + std::to_string(c.U.map.rows()) +
                " rows");
  return without_gil([&] {
    auto contact = pipeline::make_surface_contact(c.U.map, c.T, p.map, o, co, mass, gravity);
    auto driver = std::make_unique<ContactDriving>(simulator, std::move(contact));
    return std::make_unique<Object>(c.U.map, c.T, interp::embed(c.U.map, c.T, p.map), std::move(driver), o);
  });
}

std::unique_ptr<Object> from_scene(const py::object& path, const std::optional<std::string>& method) {
  scenes::Scene sc = scenes::load_scene(py::str(path).cast<std::string>());
  if (method) sc.interpolation.method = pipeline::kMethodNames.parse(*method, "method");
  return without_gil([&] {
    const scenes::SceneModels m = scenes::load_models(sc);
    return std::make_unique<Object>(scenes::make_pipeline(sc, m, interp::embed(m.U, m.T, m.dense.V)));
  });
}

// The last frame's contact figures, or None for a pipeline without contact at the dense points.
py::object contact_of(Object& b) {
  struct Figures {
    bool surface = false;
    int touching = 0, newton = 0, halvings = 0, colliders = 0;
    double stiffness = 0;
  };
  const Figures f = b.run([](pipeline::FramePipeline& x) {
    Figures r;
    const pipeline::SurfaceContact* contact = nullptr;
    const sim::StepResult* step = nullptr;
    if (const auto* s = dynamic_cast<const pipeline::SimulatorDriver*>(&x.driver()); s && s->contact()) {
      contact = s->contact().get();
      step = &s->last_step();
      r.touching = s->touching_points();
    } else if (const auto* d = dynamic_cast<const ContactDriving*>(&x.driver())) {
      contact = &d->contact();
      step = &d->last_step();
      r.touching = d->touching_points();
    }
    if (!contact) return r;
    r.surface = true;
    r.newton = step->newton_iterations;
    r.halvings = step->line_search_halvings;
    r.colliders = static_cast<int>(contact->colliders().size());
    r.stiffness = contact->stiffness();
    return r;
  });
  if (!f.surface) return py::none();
  py::dict d;
  d["touching"] = f.touching;
  d["newton_iterations"] = f.newton;
  d["line_search_halvings"] = f.halvings;
  d["colliders"] = f.colliders;
  d["stiffness"] = f.stiffness;
  return d;
}

// A collider as built, checked (mbi.Error naming the field).
Collider checked(Collider c, const char* name) {
  pipeline::check_collider(c, name);
  return c;
}

Collider moving(const Collider& c, const py::object& velocity, double twist_rate, const py::object& twist_axis,
                const py::object& twist_center, double start, double stop) {
  Collider out = c;
  out.motion.velocity = vector3(velocity, "velocity");
  out.motion.angular_velocity = twist_rate;
  out.motion.axis = vector3(twist_axis, "twist_axis");
  out.motion.center = vector3(twist_center, "twist_center");
  out.motion.start = start;
  out.motion.stop = stop;
  return checked(out, "motion");
}

// A closed triangle mesh (V (n, 3), F (t, 3)) as a level-set collider; the GIL is let go while
// OpenVDB builds the grid on its threads.
Collider mesh_collider(const py::object& V, const py::object& F, double friction, const py::object& voxel_size,
                       double band_voxels) {
  const Eigen::MatrixXd v = float_matrix(V, "V", {-1, 3}).map;
  const Eigen::MatrixXi f = index_matrix(F, "F", {-1, 3});
  pipeline::MeshLevelSetOptions options;
  if (!voxel_size.is_none()) options.voxel_size = voxel_size.cast<double>();
  options.band_voxels = band_voxels;
  std::shared_ptr<const pipeline::MeshLevelSet> level_set;
  {
    py::gil_scoped_release free;
    level_set = std::make_shared<const pipeline::MeshLevelSet>(v, f, options);
  }
  return checked(Collider::mesh(std::move(level_set), friction), "mesh");
}

std::string repr(const Collider& c) {
  std::ostringstream o;
  o << "Collider." << scenes::kColliderShapeNames.name(c.shape) << "(friction=" << c.friction << ")";
  return o.str();
}

void bind_collider(py::module_& m) {
  const auto zero = py::make_tuple(0.0, 0.0, 0.0);
  py::class_<Collider>(m, "Collider",
      "A rigid collider (plane, sphere, box, capsule, closed triangle mesh) that the dense points touch, static or "
      "moving; m, s.")
      .def_static("plane", [](const py::object& point, const py::object& normal, double friction) {
        return checked(Collider::plane(vector3(point, "point"), vector3(normal, "normal"), friction), "plane");
      }, py::arg("point"), py::arg("normal"), py::kw_only(), py::arg("friction") = 0.0,
         "solid where normal . (x - point) < 0")
      .def_static("sphere", [](const py::object& center, double radius, double friction) {
        return checked(Collider::sphere(vector3(center, "center"), radius, friction), "sphere");
      }, py::arg("center"), py::arg("radius"), py::kw_only(), py::arg("friction") = 0.0)
      .def_static("box", [](const py::object& center, const py::object& half_extents, const py::object& axes,
                            double friction) {
        Eigen::Matrix3d A = Eigen::Matrix3d::Identity();
        if (!axes.is_none()) A = float_matrix(axes, "axes", {3, 3}).map.transpose();  // rows: the axes
        return checked(Collider::box(vector3(center, "center"), vector3(half_extents, "half_extents"), A, friction),
                       "box");
      }, py::arg("center"), py::arg("half_extents"), py::arg("axes") = py::none(), py::kw_only(),
         py::arg("friction") = 0.0, "axes: (3, 3), its rows the box's unit axes (default the coordinate axes)")
      .def_static("capsule", [](const py::object& a, const py::object& b, double radius, double friction) {
        return checked(Collider::capsule(vector3(a, "a"), vector3(b, "b"), radius, friction), "capsule");
      }, py::arg("a"), py::arg("b"), py::arg("radius"), py::kw_only(), py::arg("friction") = 0.0)
      .def_static("mesh", &mesh_collider, py::arg("V"), py::arg("F"), py::kw_only(), py::arg("friction") = 0.0,
                  py::arg("voxel_size") = py::none(), py::arg("band_voxels") = 3.0,
                  "a closed triangle mesh V (n, 3), F (t, 3) as OpenVDB's signed distance field "
                  "(docs/mesh-colliders.md): voxel_size (m, default the bounding box's diagonal / 128), "
                  "band_voxels outside it; distances within a voxel")
      .def("moving", &moving, py::kw_only(), py::arg("velocity") = zero, py::arg("twist_rate") = 0.0,
           py::arg("twist_axis") = py::make_tuple(0.0, 0.0, 1.0), py::arg("twist_center") = zero,
           py::arg("start") = 0.0, py::arg("stop") = 1e300,
           "the collider moving rigidly from its pose at `start` (s) to `stop`: velocity (m/s), twist_rate "
           "(rad/s) about twist_axis through twist_center, as a kinematic constraint's motion")
      .def("distance", [](const Collider& c, const py::object& p, double time) {
        const pipeline::Distance d = pipeline::signed_distance(c, vector3(p, "p"), time);
        return py::make_tuple(d.value, to_numpy_vector(d.normal));
      }, py::arg("p"), py::arg("time") = 0.0, "(signed distance (m, < 0 inside), unit outward normal) at p")
      .def("distances", &distances, py::arg("P"), py::arg("time") = 0.0,
           "(signed distances (p,) (m, < 0 inside), unit outward normals (p, 3)) at the points P (p, 3)")
      .def_property_readonly("shape", [](const Collider& c) { return std::string(scenes::kColliderShapeNames.name(c.shape)); })
      .def_property_readonly("friction", [](const Collider& c) { return c.friction; })
      .def_property_readonly("radius", [](const Collider& c) { return c.radius; })
      .def("__repr__", &repr);
}

void bind_pipeline_contact(py::module_& m) {
  auto cls = py::reinterpret_borrow<py::class_<Object>>(m.attr("FramePipeline"));
  cls.def_static("with_contact", &with_contact, py::arg("U"), py::arg("T"), py::arg("P"), py::arg("simulator"),
                 py::arg("colliders"), py::kw_only(), py::arg("stiffness") = py::none(), py::arg("points") = py::none(),
                 py::arg("method") = "modified-bi", py::arg("alpha") = py::none(), py::arg("beta") = 0.0,
                 py::arg("pin_boundary") = false,
                 "A pipeline whose simulator steps with contact at the dense points P (or the rows `points`) "
                 "against `colliders` (scene key contact = \"surface\"); the simulator takes the contact as its "
                 "potential. stiffness: N/m per point (default 1e4 m g / diagonal).")
      .def_static("from_scene", &from_scene, py::arg("path"), py::kw_only(), py::arg("method") = py::none(),
                  "The pipeline of a scene file as `mbi run` builds it (contact keys included; CPU, float64)")
      .def_property_readonly("contact", &contact_of,
                             "the last frame's contact at the dense points: {touching, newton_iterations, "
                             "line_search_halvings, colliders, stiffness}, or None without");
}

}  // namespace

void bind_contact(py::module_& m) {
  bind_collider(m);
  bind_pipeline_contact(m);
}

}  // namespace mbi::python
