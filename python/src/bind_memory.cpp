// The memory of a modified-BI run before it is made: mbi.estimate_memory (the factor's symbolic
// analysis, as mbi deform --stats prints it), mbi.memory_limit, and the max_memory argument.
#include "bindings.hpp"

#include <mbi/interp/memory.hpp>

#include <cmath>
#include <string>

namespace mbi::python {

double max_memory_arg(const py::object& value) {
  if (value.is_none()) return 0.0;
  if (py::isinstance<py::str>(value)) {
    try {
      return interp::parse_memory_size(value.cast<std::string>());
    } catch (const mbi::Error& e) {
      throw Error(std::string("max_memory: ") + e.what());
    }
  }
  // numbers: Python's and numpy's scalars alike; not booleans, not arrays
  if (py::isinstance<py::bool_>(value) || py::isinstance<py::array>(value) || !PyNumber_Check(value.ptr()))
    throw Error("max_memory must be bytes (a number > 0) or a size such as '8G', not " +
                py::str(value.get_type()).cast<std::string>());
  const double bytes = py::float_(value).cast<double>();
  if (!(bytes > 0) || !std::isfinite(bytes))
    throw Error("max_memory must be a finite number of bytes > 0, got " + py::repr(value).cast<std::string>());
  return bytes;
}

namespace {

interp::MemoryEstimate estimate(const py::object& U, const py::object& T, long long dense_points, bool pin_boundary,
                                const std::string& solve_path, const std::string& factorization) {
  const Mesh c = control_mesh(U, T);
  interp::Options o;
  o.pin_boundary = pin_boundary;
  o.solve_path = interp::kSolvePathNames.parse(solve_path, "solve_path");
  o.factorization = interp::kFactorizationNames.parse(factorization, "factorization");
  if (dense_points < 0) throw Error("dense_points must be >= 0, got " + std::to_string(dense_points));
  return without_gil([&] { return interp::estimate_memory(c.U.map, c.T, dense_points, o); });
}

}  // namespace

void bind_memory(py::module_& m) {
  using namespace pybind11::literals;
  using E = interp::MemoryEstimate;
  py::class_<E>(m, "MemoryEstimate", "The estimated peak memory of a modified-BI run and its parts (bytes, counts).")
      .def_readonly("unknowns", &E::unknowns, "d n: rows of the m-block")
      .def_readonly("matrix_nonzeros", &E::matrix_nonzeros)
      .def_readonly("factor_nonzeros", &E::factor_nonzeros, "values the Cholesky factor stores")
      .def_readonly("factor_flops", &E::factor_flops)
      .def_readonly("ordering", &E::ordering)
      .def_readonly("factor_bytes", &E::factor_bytes)
      .def_readonly("assembly_bytes", &E::assembly_bytes)
      .def_readonly("dense_operator_bytes", &E::dense_operator_bytes)
      .def_readonly("model_bytes", &E::model_bytes)
      .def_readonly("process_bytes", &E::process_bytes)
      .def_readonly("peak_bytes", &E::peak_bytes, "the estimated peak resident memory of the whole run")
      .def("__repr__", [](const E& e) {
        return "MemoryEstimate(peak=" + interp::format_bytes(e.peak_bytes) + ", factor=" +
               interp::format_bytes(e.factor_bytes) + ", unknowns=" + std::to_string(e.unknowns) + ")";
      });
  m.def("estimate_memory", &estimate, "U"_a, "T"_a, "dense_points"_a = 0, py::kw_only(), "pin_boundary"_a = false,
        "solve_path"_a = "automatic", "factorization"_a = "automatic",
        "The peak memory of ModifiedBI(U, T) (and of deforming dense_points points) before any numeric work: "
        "from the symbolic analysis of its Cholesky factor (seconds at 100,000 control vertices), as "
        "mbi deform --stats prints it.");
  m.def(
      "memory_limit",
      [](const py::object& max_memory) {
        std::string name;
        const double bytes = interp::memory_limit(max_memory_arg(max_memory), name);
        return py::make_tuple(bytes, name);
      },
      "max_memory"_a = py::none(),
      "(bytes, what they are): max_memory when given, else the smaller of MemAvailable and the process's "
      "memory (its control group's limit in a container); 0 when unknown.");
}

}  // namespace mbi::python
