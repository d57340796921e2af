// cage(): a control mesh around a dense surface, as `mbi cage` builds it (mbi::generate).
#include "bindings.hpp"

#include <mbi/generate/cage.hpp>

namespace mbi::python {
namespace {

using generate::CageResult;

CageResult make(const py::object& V, const py::object& F, int vertices, const std::string& mesher, bool force_3d) {
  const Input v = float_matrix(V, "V", {-1, 3});
  Eigen::MatrixXi f(0, 3);
  if (!F.is_none()) f = index_matrix(F, "F", {-1, 3});
  generate::CageOptions o;
  o.target_vertices = vertices;
  o.force_3d = force_3d;
  o.mesher = generate::parse_mesher(mesher);
  // as `mbi cage` says it: TetGen makes tetrahedra only, a flat model is 2D unless force_3d
  if (o.mesher == generate::Mesher::TetGen && !force_3d && generate::is_planar(v.map))
    throw Error("V is flat (every z = " + std::to_string(v.map(0, 2)) +
                "), a 2D input; TetGen makes tetrahedra only: use mesher=\"voxel\" for a 2D triangle cage, or "
                "force_3d=True for tetrahedra");
  try {
    return without_gil([&] { return generate::make_cage(v.map, f, o); });
  } catch (const Error& e) {  // the library's option target_vertices is the argument `vertices` here
    std::string message = e.what();
    const std::string field = "target_vertices";
    for (size_t at = message.find(field); at != std::string::npos; at = message.find(field, at))
      message.replace(at, field.size(), "vertices");
    throw Error(message);
  }
}

}  // namespace

void bind_cage(py::module_& m) {
  py::class_<CageResult>(m, "Cage", "A control mesh built around a dense model; unpacks as U, T.")
      .def_property_readonly("U", [](const CageResult& c) { return to_numpy(Eigen::Ref<const Eigen::MatrixXd>(c.U)); },
                             "(n, d) control vertices, in the units of the model")
      .def_property_readonly("T", [](const CageResult& c) { return to_numpy(c.T); },
                             "(m, d+1) tetrahedra (triangles for a flat model), positive volume")
      .def_property_readonly("dim", &CageResult::dim)
      .def_readonly("cell_size", &CageResult::cell_size, "longest grid cell edge, model units")
      .def_readonly("min_dihedral_deg", &CageResult::min_dihedral_deg, "smallest dihedral angle (2D: triangle angle), deg")
      .def_readonly("outside_points", &CageResult::outside_points, "model vertices outside the cage")
      .def_readonly("seconds", &CageResult::seconds, "wall-clock time of the generation, s")
      .def_property_readonly("mesher", [](const CageResult& c) { return std::string(generate::mesher_name(c.mesher)); })
      .def_readonly("tetgen_switches", &CageResult::tetgen_switches)
      .def("__iter__", [](const py::object& self) { return py::iter(py::make_tuple(self.attr("U"), self.attr("T"))); })
      .def("__repr__", [](const CageResult& c) {
        return "Cage(" + std::to_string(c.U.rows()) + " vertices, " + std::to_string(c.T.rows()) + " elements, " +
               generate::mesher_name(c.mesher) + ")";
      });
  m.def("cage", &make, py::arg("V"), py::arg("F") = py::none(), py::kw_only(), py::arg("vertices") = 200,
        py::arg("mesher") = "voxel", py::arg("force_3d") = false,
        "A control mesh of about `vertices` vertices around the surface V (n, 3), F (t, 3) (F may be None: a point "
        "cloud), as `mbi cage` builds it. mesher: voxel or tetgen. Deterministic.");
}

}  // namespace mbi::python
