// Simulator: the co-rotational FEM simulator of mbi::sim (material, fixed and kinematic nodes,
// point forces, poke springs, ground plane), stepped from Python.
#include "objects.hpp"

#include <mbi/base/names.hpp>

namespace mbi::python {
namespace {

using sim::Simulator;

inline constexpr auto kIntegratorNames = name_table<sim::Integrator>(
    {{sim::Integrator::BackwardEuler, "backward-euler"}, {sim::Integrator::ImplicitMidpoint, "implicit-midpoint"}});
inline constexpr auto kSolverNames = name_table<sim::LinearSolver>(
    {{sim::LinearSolver::Auto, "auto"}, {sim::LinearSolver::LDLT, "ldlt"}, {sim::LinearSolver::PCG, "pcg"}});

// One keyword of simulation_parameters: false when `key` is not one of them.
bool set_parameter(sim::Parameters& p, const std::string& key, const py::handle& v) {
  const char* k = key.c_str();
  if (key == "dt") p.dt = v.cast<double>();
  else if (key == "substeps") p.substeps = v.cast<int>();
  else if (key == "gravity") p.gravity = vector3(v, k);
  else if (key == "mass_damping") p.mass_damping = v.cast<double>();
  else if (key == "stiffness_damping") p.stiffness_damping = v.cast<double>();
  else if (key == "integrator") p.integrator = kIntegratorNames.parse(v.cast<std::string>(), k);
  else if (key == "newton_iterations") p.newton_iterations = v.cast<int>();
  else if (key == "newton_tolerance") p.newton_tolerance = v.cast<double>();
  else if (key == "solver") p.solver = kSolverNames.parse(v.cast<std::string>(), k);
  else if (key == "pcg_tolerance") p.pcg_tolerance = v.cast<double>();
  else if (key == "pcg_max_iterations") p.pcg_max_iterations = v.cast<int>();
  else if (key == "max_energy") p.max_energy = v.cast<double>();
  else if (key == "ground") {  // None: no ground; a height h: the plane y = h
    p.ground = !v.is_none();
    if (p.ground) p.ground_plane.offset = v.cast<double>();
  } else if (key == "ground_normal") p.ground_plane.normal = vector3(v, k);
  else if (key == "ground_friction") p.ground_plane.friction = v.cast<double>();
  else return false;
  return true;
}

sim::Material material(double E, double nu, double rho) {
  return {.youngs_modulus = E, .poisson_ratio = nu, .density = rho};
}

std::shared_ptr<SimulatorObject> make_simulator(const py::object& U, const py::object& T, double E, double nu,
                                                double rho, const py::object& element_materials,
                                                const py::kwargs& options) {
  const Mesh c = control_mesh(U, T);
  if (c.U.map.cols() != 3) throw Error("U must have shape (n, 3): the simulator is 3D");
  const sim::Parameters p = simulation_parameters(options, {});
  std::vector<sim::Material> per_element;
  if (!element_materials.is_none()) {
    const Input m = float_matrix(element_materials, "element_materials", {c.T.rows(), 3});
    for (Eigen::Index e = 0; e < m.map.rows(); ++e) per_element.push_back(material(m.map(e, 0), m.map(e, 1), m.map(e, 2)));
  }
  try {
    return without_gil([&] { return std::make_shared<SimulatorObject>(c.U.map, c.T, material(E, nu, rho), p, per_element); });
  } catch (const Error& e) {  // the library names the material's fields in words: name the keywords
    std::string message = e.what();
    for (const auto& [words, keyword] : {std::pair<std::string, std::string>{"Young's modulus", "youngs_modulus"},
                                         {"Poisson ratio", "poisson_ratio"}})
      if (const size_t at = message.find(words); at != std::string::npos) message.replace(at, words.size(), keyword);
    throw Error(message);
  }
}

// A material point: element index and 4 barycentric coordinates.
Eigen::Vector4d bary4(const py::object& bary) { return float_vector(bary, "bary", 4); }

void bind_step_result(py::module_& m) {
  py::class_<sim::StepResult>(m, "StepResult", "The outcome of Simulator.step().")
      .def_readonly("success", &sim::StepResult::success)
      .def_readonly("message", &sim::StepResult::message, "why the step failed ('' on success)")
      .def_readonly("step", &sim::StepResult::step, "number of this step (1 = the first)")
      .def_readonly("time", &sim::StepResult::time, "simulated time after the step, s")
      .def_readonly("newton_iterations", &sim::StepResult::newton_iterations)
      .def_readonly("solver_iterations", &sim::StepResult::solver_iterations, "PCG iterations (0 for LDLT)")
      .def_readonly("total_ms", &sim::StepResult::total_ms)
      .def("__bool__", [](const sim::StepResult& r) { return r.success; })
      .def("__repr__", [](const sim::StepResult& r) {
        return "StepResult(success=" + std::string(r.success ? "True" : "False") + ", step=" + std::to_string(r.step) +
               ", time=" + std::to_string(r.time) + (r.success ? "" : ", message='" + r.message + "'") + ")";
      });
  py::class_<sim::StaticResult>(m, "StaticResult", "The outcome of Simulator.solve_static().")
      .def_readonly("converged", &sim::StaticResult::converged)
      .def_readonly("iterations", &sim::StaticResult::iterations)
      .def_readonly("residual", &sim::StaticResult::residual, "max free-node force imbalance, N")
      .def_readonly("message", &sim::StaticResult::message);
}

}  // namespace

sim::Parameters simulation_parameters(const py::dict& options, sim::Parameters base) {
  for (const auto& [key, value] : options) {
    const std::string k = key.cast<std::string>();
    try {
      if (!set_parameter(base, k, value)) throw Error("unknown simulation parameter \"" + k + "\"");
    } catch (const py::cast_error&) {
      throw Error(k + " must be a number, got " + py::repr(value).cast<std::string>());
    }
  }
  return base;
}

namespace {

using Object = SimulatorObject;

void bind_handles(py::class_<Object, std::shared_ptr<Object>>& c) {
  c.def("fix", [](Object& s, const py::object& nodes) {
       const std::vector<int> n = index_list(nodes, "nodes", s.object.nodes());
       return s.run([&](Simulator& x) { return x.fix(n); });
     }, py::arg("nodes"), "Holds the nodes at their current positions; returns the handle.")
      .def("add_kinematic", [](Object& s, const py::object& nodes, const py::object& center, const py::object& axis,
                               double angular_velocity, const py::object& velocity, double start, double stop) {
        const std::vector<int> n = index_list(nodes, "nodes", s.object.nodes());
        if (stop < start)
          throw Error("stop (" + std::to_string(stop) + " s) is before start (" + std::to_string(start) + " s)");
        const sim::RigidMotion motion{vector3(center, "center"), vector3(axis, "axis"), angular_velocity,
                                      vector3(velocity, "velocity"), start, stop};
        return s.run([&](Simulator& x) { return x.add_kinematic(n, motion); });
      }, py::arg("nodes"), py::kw_only(), py::arg("center") = py::make_tuple(0, 0, 0),
         py::arg("axis") = py::make_tuple(1, 0, 0), py::arg("angular_velocity") = 0.0,
         py::arg("velocity") = py::make_tuple(0, 0, 0), py::arg("start") = 0.0, py::arg("stop") = 1e300,
         "Nodes moving rigidly: rotation about `axis` through `center` (rad/s) and translation (m/s), "
         "on [start, stop] (s); returns the handle.")
      .def("add_point_force", [](Object& s, int element, const py::object& bary, const py::object& force) {
        const Eigen::Vector4d b = bary4(bary);
        const Eigen::Vector3d f = vector3(force, "force");
        return s.run([&](Simulator& x) { return x.add_point_force(element, b, f); });
      }, py::arg("element"), py::arg("bary"), py::arg("force"), "Constant force (N) at a material point; returns the handle.")
      .def("set_point_force", [](Object& s, int handle, const py::object& force) {
        const Eigen::Vector3d f = vector3(force, "force");
        s.run([&](Simulator& x) { x.set_point_force(handle, f); });
      }, py::arg("handle"), py::arg("force"))
      .def("add_poke", [](Object& s, int element, const py::object& bary, const py::object& target, double k) {
        const Eigen::Vector4d b = bary4(bary);
        const Eigen::Vector3d t = vector3(target, "target");
        return s.run([&](Simulator& x) { return x.add_poke(element, b, t, k); });
      }, py::arg("element"), py::arg("bary"), py::arg("target"), py::arg("stiffness"),
         "Zero-length spring (N/m) pulling a material point toward target (m); returns the handle.")
      .def("set_poke_target", [](Object& s, int handle, const py::object& target) {
        const Eigen::Vector3d t = vector3(target, "target");
        s.run([&](Simulator& x) { x.set_poke_target(handle, t); });
      }, py::arg("handle"), py::arg("target"))
      .def("remove", [](Object& s, int handle) { s.run([&](Simulator& x) { x.remove(handle); }); }, py::arg("handle"))
      .def("has_handle", [](Object& s, int handle) { return s.run([&](Simulator& x) { return x.has_handle(handle); }); },
           py::arg("handle"));
}

// A read of the state: the simulator's matrix copied into a new array.
template <class F>
py::array state(Object& s, F&& get) {
  Eigen::MatrixXd A = s.run([&](Simulator& x) { return Eigen::MatrixXd(get(x)); });
  return to_numpy(std::move(A));
}

template <class F>
double scalar(Object& s, F&& get) {
  return s.run([&](Simulator& x) { return get(x); });
}

void bind_state(py::class_<Object, std::shared_ptr<Object>>& c) {
  c.def("step", [](Object& s) { return s.run([](Simulator& x) { return x.step(); }); },
        "Advances by dt; on failure the state stays at the last good step (result.success False).")
      .def("solve_static", [](Object& s, int max_iterations, double tolerance) {
        return s.run([&](Simulator& x) { return x.solve_static(max_iterations, tolerance); });
      }, py::arg("max_iterations") = 100, py::arg("tolerance") = 0.0)
      .def("reset", [](Object& s) { s.run([](Simulator& x) { x.reset(); }); })
      .def_property_readonly("positions", [](Object& s) { return state(s, [](Simulator& x) { return x.positions(); }); },
                             "(n, 3) node positions, m (a copy)")
      .def_property_readonly("velocities", [](Object& s) { return state(s, [](Simulator& x) { return x.velocities(); }); },
                             "(n, 3) node velocities, m/s (a copy)")
      .def_property_readonly("rest_positions", [](Object& s) { return state(s, [](Simulator& x) { return x.rest_positions(); }); })
      .def_property_readonly("masses", [](Object& s) {
        Eigen::VectorXd v = s.run([](Simulator& x) { return Eigen::VectorXd(x.masses()); });
        return to_numpy_vector(v);
      }, "(n,) lumped node masses, kg")
      .def("elastic_forces", [](Object& s) { return state(s, [](Simulator& x) { return x.elastic_forces(); }); },
           "(n, 3) elastic node forces at the current positions, N")
      .def("set_positions", [](Object& s, const py::object& X) {
        const Input x = float_matrix(X, "X", {s.object.nodes(), 3});
        s.run([&](Simulator& y) { y.set_positions(x.map); });
      }, py::arg("X"))
      .def("set_velocities", [](Object& s, const py::object& V) {
        const Input v = float_matrix(V, "V", {s.object.nodes(), 3});
        s.run([&](Simulator& y) { y.set_velocities(v.map); });
      }, py::arg("V"))
      .def_property_readonly("time", [](Object& s) { return scalar(s, [](Simulator& x) { return x.time(); }); }, "s")
      .def_property_readonly("step_count", [](Object& s) { return s.run([](Simulator& x) { return x.step_count(); }); })
      .def("kinetic_energy", [](Object& s) { return scalar(s, [](Simulator& x) { return x.kinetic_energy(); }); }, "J")
      .def("elastic_energy", [](Object& s) { return scalar(s, [](Simulator& x) { return x.elastic_energy(); }); }, "J")
      .def("gravity_energy", [](Object& s) { return scalar(s, [](Simulator& x) { return x.gravity_energy(); }); }, "J")
      .def("volume", [](Object& s) { return scalar(s, [](Simulator& x) { return x.volume(); }); }, "m^3, signed")
      .def("rest_volume", [](Object& s) { return scalar(s, [](Simulator& x) { return x.rest_volume(); }); }, "m^3")
      .def("linear_momentum", [](Object& s) {
        const Eigen::VectorXd v = s.run([](Simulator& x) { return Eigen::VectorXd(x.linear_momentum()); });
        return to_numpy_vector(v);
      }, "(3,) kg m/s")
      .def("angular_momentum", [](Object& s) {
        const Eigen::VectorXd v = s.run([](Simulator& x) { return Eigen::VectorXd(x.angular_momentum()); });
        return to_numpy_vector(v);
      }, "(3,) kg m^2/s about the origin");
}

}  // namespace

void bind_sim(py::module_& m) {
  bind_step_result(m);
  py::class_<Object, std::shared_ptr<Object>> c(m, "Simulator",
      "Co-rotational FEM simulator of a tetrahedral control mesh, SI units (m, s, kg, N, Pa, J).");
  c.def(py::init(&make_simulator), py::arg("U"), py::arg("T"), py::kw_only(), py::arg("youngs_modulus") = 1e5,
        py::arg("poisson_ratio") = 0.45, py::arg("density") = 1000.0, py::arg("element_materials") = py::none(),
        "U (n, 3) rest positions (m), T (m, 4) tetrahedra. Material: E (Pa), nu, rho (kg/m^3), or "
        "element_materials (m, 3) rows (E, nu, rho). Keyword parameters: dt (s), substeps, gravity "
        "(m/s^2), mass_damping (1/s), stiffness_damping (s), integrator, newton_iterations, "
        "newton_tolerance (m/s), solver, pcg_tolerance, pcg_max_iterations, max_energy (J), ground "
        "(None or the height y of a ground plane, m), ground_normal, ground_friction.");
  bind_handles(c);
  bind_state(c);
  c.def("set_params", [](Object& s, const py::kwargs& options) {
     const sim::Parameters p = simulation_parameters(options, s.object.params());
     s.run([&](Simulator& x) { x.set_params(p); });
   }, "Changes the keyword parameters given (those of the constructor); the mesh stays.")
      .def_property_readonly("nodes", [](Object& s) { return s.object.nodes(); })
      .def_property_readonly("elements", [](Object& s) { return s.object.elements(); })
      .def_property_readonly("dt", [](Object& s) { return s.object.params().dt; }, "s per step")
      .def_property_readonly("solver", [](Object& s) { return kSolverNames.name(s.object.solver()); },
                             "the linear solver in use (auto resolved)");
  m.attr("INTEGRATORS") = py::tuple(py::cast(kIntegratorNames.names()));
  m.attr("SOLVERS") = py::tuple(py::cast(kSolverNames.names()));
}

}  // namespace mbi::python
