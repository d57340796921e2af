// FramePipeline and its drivers: a Simulator stepped once a frame, handles dragged without
// physics (HandleDriver), or positions given from outside (GivenDriver), then M, the Bezier
// points and the dense points each frame, as `mbi run` and `mbi deform` compute them.
#include "objects.hpp"

#include <mbi/interp/embed.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>
#include <mbi/scenes/scene.hpp>

#include <mutex>

namespace mbi::python {
namespace {

using pipeline::Driver;
using pipeline::DriveResult;
using pipeline::FramePipeline;

// A driver that Python holds too: the pipeline's calls take the object's lock, as Python's do.
template <class D>
class SharedDriver final : public Driver {
 public:
  explicit SharedDriver(std::shared_ptr<Guarded<D>> d) : d_(std::move(d)) {}
  DriveResult drive(int frame, Eigen::MatrixXd& X) override {
    std::lock_guard<std::mutex> lock(d_->mutex);
    return d_->object.drive(frame, X);
  }
  const interp::VertexMatrices* solved_M() const override { return d_->object.solved_M(); }
  void reset() override {
    std::lock_guard<std::mutex> lock(d_->mutex);
    d_->object.reset();
  }
  const char* name() const override { return d_->object.name(); }

 private:
  std::shared_ptr<Guarded<D>> d_;
};

// A Simulator that Python holds: stepped once a frame (not for frame 0, the initial pose), as
// pipeline::SimulatorDriver steps the simulator it owns; pokes and forces are set from Python.
class SimulatorDriving final : public Driver {
 public:
  explicit SimulatorDriving(std::shared_ptr<SimulatorObject> s) : s_(std::move(s)) {}
  DriveResult drive(int frame, Eigen::MatrixXd& X) override {
    std::lock_guard<std::mutex> lock(s_->mutex);
    if (frame > 0) {
      const sim::StepResult r = s_->object.step();
      if (!r.success) return {false, r.message};
    }
    X = s_->object.positions();
    return {};
  }
  void reset() override {
    std::lock_guard<std::mutex> lock(s_->mutex);
    s_->object.reset();
  }
  const char* name() const override { return "simulation"; }

 private:
  std::shared_ptr<SimulatorObject> s_;
};

std::unique_ptr<Driver> driver_of(const py::object& driver, const ConstMap& U) {
  if (driver.is_none()) return std::make_unique<pipeline::GivenDriver>(U);
  if (py::isinstance<SimulatorObject>(driver))
    return std::make_unique<SimulatorDriving>(driver.cast<std::shared_ptr<SimulatorObject>>());
  if (py::isinstance<HandleDriverObject>(driver))
    return std::make_unique<SharedDriver<pipeline::HandleDriver>>(driver.cast<std::shared_ptr<HandleDriverObject>>());
  if (py::isinstance<GivenDriverObject>(driver))
    return std::make_unique<SharedDriver<pipeline::GivenDriver>>(driver.cast<std::shared_ptr<GivenDriverObject>>());
  throw Error("driver must be None, a Simulator, a HandleDriver or a GivenDriver, got " +
              py::str(py::type::of(driver)).cast<std::string>());
}

interp::Options interp_options(std::optional<double> alpha, double beta, bool pin_boundary) {
  interp::Options o;
  o.alpha = alpha;
  o.beta = beta;
  o.pin_boundary = pin_boundary;
  return o;
}

using Object = Guarded<FramePipeline>;

std::unique_ptr<Object> make_pipeline(const py::object& U, const py::object& T, const py::object& P,
                                      const py::object& driver, const std::string& method, std::optional<double> alpha, double beta,
                                      bool pin_boundary, const py::object& rest_normals,
                                      std::optional<double> max_outside) {
  const Mesh c = control_mesh(U, T);
  const Input p = float_matrix(P, "P", {-1, c.U.map.cols()});
  pipeline::PipelineOptions o;
  o.method = pipeline::kMethodNames.parse(method, "method");
  o.interp = interp_options(alpha, beta, pin_boundary);
  Eigen::MatrixXd normals;
  if (!rest_normals.is_none()) {
    normals = float_matrix(rest_normals, "rest_normals", {p.map.rows(), p.map.cols()}).map;
    o.normals = true;
  }
  std::unique_ptr<Driver> d = driver_of(driver, c.U.map);
  interp::Embedding e = without_gil([&] { return interp::embed(c.U.map, c.T, p.map); });
  report_outside(e, p, max_outside);
  return without_gil([&] {
    return std::make_unique<Object>(c.U.map, c.T, std::move(e), std::move(d), o, nullptr, normals);
  });
}

// A result of the current frame, copied (C order) so that the next step() leaves it alone.
template <class F>
py::array copy_of(Object& b, F&& get) {
  const Eigen::MatrixXd A = b.run([&](FramePipeline& x) { return Eigen::MatrixXd(get(x)); });
  return to_numpy(Eigen::Ref<const Eigen::MatrixXd>(A));
}

// step() `frames` times, the dense positions of each frame stacked (frames, p, d); a failing
// frame raises with the driver's message.
py::array run_frames(Object& b, int frames) {
  if (frames < 1) throw Error("frames must be >= 1, got " + std::to_string(frames));
  const Eigen::Index p = b.object.embedding().size(), d = b.object.dim();
  Output out = float_output(py::none(), "out", p, d, {frames, true});
  b.run([&](FramePipeline& x) {
    for (int k = 0; k < frames; ++k) {
      const pipeline::FrameResult r = x.step();
      if (!r.ok) throw Error("frame " + std::to_string(x.frame() + 1) + ": " + r.message);
      out.map.middleRows(k * p, p) = x.positions();
    }
  });
  return out.finish();
}

py::dict timings(const pipeline::FrameTimings& t) {
  py::dict d;
  d["drive_ms"] = t.drive_ms;
  d["solve_ms"] = t.solve_ms;
  d["bezier_ms"] = t.bezier_ms;
  d["evaluate_ms"] = t.evaluate_ms;
  d["total_ms"] = t.total_ms();
  return d;
}

void bind_drivers(py::module_& m) {
  py::class_<HandleDriverObject, std::shared_ptr<HandleDriverObject>>(m, "HandleDriver",
      "Control vertices dragged without physics (hard or soft handles); M solved with the positions.")
      .def(py::init([](const py::object& U, const py::object& T, const py::object& handles, const std::string& mode,
                       std::optional<double> alpha, double beta, bool pin_boundary, double gamma, double regularization) {
             const Mesh c = control_mesh(U, T);
             interp::ControlOptions o;
             o.interp = interp_options(alpha, beta, pin_boundary);
             o.mode = scenes::kHandleModeNames.parse(mode, "mode");
             o.gamma = gamma;
             o.regularization = regularization;
             std::vector<int> h = index_list(handles, "handles", c.U.map.rows());
             return without_gil([&] { return std::make_shared<HandleDriverObject>(c.U.map, c.T, std::move(h), o); });
           }), py::arg("U"), py::arg("T"), py::arg("handles"), py::kw_only(), py::arg("mode") = "hard",
           py::arg("alpha") = py::none(), py::arg("beta") = 0.0, py::arg("pin_boundary") = false, py::arg("gamma") = 0.0,
           py::arg("regularization") = 1e-6)
      .def("set_targets", [](HandleDriverObject& h, const py::object& targets) {
        const Input t = float_matrix(targets, "targets", {static_cast<Eigen::Index>(h.object.handles().size()), -1});
        h.run([&](pipeline::HandleDriver& x) { x.set_targets(t.map); });
      }, py::arg("targets"), "(handles, d) positions of the handles for the next frames")
      .def_property_readonly("handles", [](HandleDriverObject& h) { return h.object.handles(); });
  py::class_<GivenDriverObject, std::shared_ptr<GivenDriverObject>>(m, "GivenDriver",
      "Control positions from outside: one pose (n, d) changed by set(), or a sequence (frames, n, d).")
      .def(py::init([](const py::object& X) {
             Frames frames;
             const Input x = float_batch(X, "X", {}, frames);
             if (!frames.batch) return std::make_shared<GivenDriverObject>(x.map);
             if (frames.count == 0) throw Error("X must have at least one frame, got shape (0, n, d)");
             const Eigen::Index n = x.map.rows() / frames.count;
             std::vector<Eigen::MatrixXd> sequence;
             for (Eigen::Index k = 0; k < frames.count; ++k) sequence.emplace_back(x.map.middleRows(k * n, n));
             return std::make_shared<GivenDriverObject>(std::move(sequence));
           }), py::arg("X"))
      .def("set", [](GivenDriverObject& g, const py::object& X) {
        const Input x = float_matrix(X, "X");
        g.run([&](pipeline::GivenDriver& y) { y.set(x.map); });
      }, py::arg("X"), "the pose of the next frames");
}


void bind_frame_pipeline(py::module_& m) {
  py::class_<pipeline::FrameResult>(m, "FrameResult", "The outcome of FramePipeline.step().")
      .def_readonly("ok", &pipeline::FrameResult::ok)
      .def_readonly("message", &pipeline::FrameResult::message)
      .def_readonly("frame", &pipeline::FrameResult::frame)
      .def("__bool__", [](const pipeline::FrameResult& r) { return r.ok; });
  py::class_<Object>(m, "FramePipeline",
      "Per frame: drive the control mesh, solve M, Bezier points, dense points (CPU, float64).")
      .def(py::init(&make_pipeline), py::arg("U"), py::arg("T"), py::arg("P"), py::arg("driver") = py::none(),
           py::kw_only(), py::arg("method") = "modified-bi", py::arg("alpha") = py::none(), py::arg("beta") = 0.0,
           py::arg("pin_boundary") = false, py::arg("rest_normals") = py::none(), py::arg("max_outside") = py::none(),
           "Points of P outside the control mesh warn (mbi.OutsideWarning); max_outside refuses those farther "
           "out than max_outside x the model size (the diagonal of P's bounding box), as mbi deform --max-outside.")
      .def_property_readonly("outside_points", [](Object& b) { return b.object.embedding().outside.size(); },
                             "points outside the control mesh")
      .def_property_readonly("max_outside_distance", [](Object& b) { return b.object.embedding().max_outside_distance; },
                             "the farthest outside point's distance to the mesh (units of P)")
      .def("step", [](Object& b, bool evaluate) { return b.run([&](FramePipeline& x) { return x.step(evaluate); }); },
           py::arg("evaluate") = true, "Computes the next frame (the first call gives frame 0, the initial pose).")
      .def("run", &run_frames, py::arg("frames"), "step() `frames` times: the positions (frames, p, d)")
      .def("reset", [](Object& b) { b.run([](FramePipeline& x) { x.reset(); }); })
      .def_property_readonly("frame", [](Object& b) { return b.object.frame(); })
      .def_property_readonly("positions", [](Object& b) { return copy_of(b, [](FramePipeline& x) { return x.positions(); }); },
                             "(p, d) dense positions of the current frame")
      .def_property_readonly("normals", [](Object& b) { return copy_of(b, [](FramePipeline& x) { return x.normals(); }); })
      .def_property_readonly("control_positions",
                             [](Object& b) { return copy_of(b, [](FramePipeline& x) { return x.control_positions(); }); })
      .def_property_readonly("M", [](Object& b) { return copy_of(b, [](FramePipeline& x) { return x.M(); }); })
      .def_property_readonly("timings", [](Object& b) { return timings(b.object.timings()); }, "ms of the last frame's phases")
      .def_property_readonly("method", [](Object& b) { return pipeline::kMethodNames.name(b.object.method()); })
      .def("set_method", [](Object& b, const std::string& method) {
        const pipeline::Method me = pipeline::kMethodNames.parse(method, "method");
        b.run([&](FramePipeline& x) { x.set_method(me); });
      }, py::arg("method"))
      .def("set_alpha", [](Object& b, double alpha) { b.run([&](FramePipeline& x) { x.set_alpha(alpha); }); }, py::arg("alpha"))
      .def("evaluate_with", [](Object& b, const std::string& method) {
        const pipeline::Method me = pipeline::kMethodNames.parse(method, "method");
        Eigen::MatrixXd out;
        b.run([&](FramePipeline& x) { x.evaluate_with(me, out); });
        return to_numpy(Eigen::Ref<const Eigen::MatrixXd>(out));
      }, py::arg("method"), "the current frame's dense positions with another method")
      .def_property_readonly("driver", [](Object& b) { return std::string(b.object.driver().name()); },
                             "'simulation', 'handles' or 'given'")
      .def_property_readonly("dim", [](Object& b) { return b.object.dim(); });
}

}  // namespace

void bind_pipeline(py::module_& m) {
  bind_drivers(m);
  bind_frame_pipeline(m);
}

}  // namespace mbi::python
