// run_scene(): a scene file run headless as `mbi run` runs it (mbi::scenes), returning the
// run's outcome; python/mbi/scenes.py adds the metrics the run wrote.
#include "bindings.hpp"

#include <mbi/scenes/runner.hpp>

namespace mbi::python {
namespace {

py::dict run(const std::string& file, const py::object& out, int frames, const py::object& mesh,
             const py::object& method, const py::object& gpu, bool force, bool force_3d) {
  scenes::Scene scene = scenes::load_scene(file);
  scenes::RunOptions o;
  if (!out.is_none()) o.out_dir = py::str(out).cast<std::string>();
  o.frames = frames;
  if (!mesh.is_none()) o.mesh = py::str(mesh).cast<std::string>();
  if (!method.is_none()) o.method = pipeline::kMethodNames.parse(method.cast<std::string>(), "method");
  if (!gpu.is_none()) o.gpu = scenes::kGpuUseNames.parse(gpu.cast<std::string>(), "gpu");
  o.force = force;
  o.force_3d = force_3d;
  std::vector<std::string> warnings;  // collected without the GIL, handed over after
  o.warn = [&](const std::string& s) { warnings.push_back(s); };
  const scenes::RunResult r = without_gil([&] { return scenes::run_scene(scene, o); });
  py::dict d;
  d["scene"] = scene.name;
  d["out_dir"] = r.out_dir.string();
  d["frames"] = r.frames;
  d["failed"] = r.failed;
  d["message"] = r.message;
  d["evaluator"] = r.evaluator;
  d["outside_points"] = r.outside_points;
  d["last_table"] = r.last_table;
  d["roundoff"] = r.roundoff;
  d["warnings"] = warnings;
  return d;
}

}  // namespace

void bind_scene(py::module_& m) {
  m.def("_run_scene", &run, py::arg("path"), py::arg("out") = py::none(), py::arg("frames") = 0,
        py::arg("mesh") = py::none(), py::arg("method") = py::none(), py::arg("gpu") = py::none(),
        py::arg("force") = false, py::arg("force_3d") = false);
}

}  // namespace mbi::python
