// Embedding, embed() and the control-mesh helpers (HarmonicExtension among them).
#include "bindings.hpp"

#include <mbi/interp/embed.hpp>
#include <mbi/interp/harmonic.hpp>
#include <mbi/interp/mesh.hpp>
#include <mbi/interp/modified_bi.hpp>
#include <mbi/interp/threads.hpp>

namespace mbi::python {
namespace {

using interp::Embedding;

py::array element_view(const py::object& self) {
  const Embedding& e = self.cast<const Embedding&>();
  return readonly_view(py::dtype::of<int>(), {e.size()}, {sizeof(int)}, e.element.data(), self);
}

py::array bary_view(const py::object& self) {
  const Embedding& e = self.cast<const Embedding&>();
  const py::ssize_t s = sizeof(double);
  return readonly_view(py::dtype::of<double>(), {e.bary.rows(), e.bary.cols()}, {s, s * e.bary.rows()},
                       e.bary.data(), self);
}

py::array gradients_view(const py::object& self) {
  const Embedding& e = self.cast<const Embedding&>();
  const py::ssize_t s = sizeof(double);
  return readonly_view(py::dtype::of<double>(), {e.gradients.rows(), e.gradients.cols()},
                       {s, s * e.gradients.rows()}, e.gradients.data(), self);
}

py::array outside_view(const py::object& self) {
  const Embedding& e = self.cast<const Embedding&>();
  return readonly_view(py::dtype::of<int>(), {static_cast<py::ssize_t>(e.outside.size())}, {sizeof(int)},
                       e.outside.data(), self);
}

py::array node_array(const Eigen::VectorXi& v) { return py::array_t<int>(v.size(), v.data()); }

}  // namespace

void bind_embedding(py::module_& m) {
  using namespace pybind11::literals;
  py::class_<Embedding>(m, "Embedding",
                        "Dense points located in a control mesh: per point an element and its barycentric "
                        "coordinates (read-only arrays; made by embed()).")
      .def_property_readonly("element", element_view, "(p,) int32: the element holding (or nearest to) each point")
      .def_property_readonly("bary", bary_view, "(p, d+1) float64: barycentric coordinates in that element (sum 1)")
      .def_property_readonly("outside", outside_view,
                             "(k,) int32: points outside every element, extrapolated from the nearest one")
      .def_property_readonly("max_outside_distance", [](const Embedding& e) { return e.max_outside_distance; },
                             "largest distance of an outside point to the mesh (units of the points)")
      .def_property_readonly("gradients", gradients_view,
                             "(m (d+1), d) float64: each element's basis gradients (for normals)")
      .def_property_readonly("dim", &Embedding::dim, "d: 2 or 3")
      .def_property_readonly("size", &Embedding::size, "p: the number of points")
      .def("__len__", &Embedding::size)
      .def("__repr__", [](const Embedding& e) {
        return "<mbi.Embedding of " + std::to_string(e.size()) + " points in " + std::to_string(e.dim()) +
               "D, " + std::to_string(e.outside.size()) + " outside>";
      });

  m.def(
      "embed",
      [](const py::object& U, const py::object& T, const py::object& P, std::optional<double> max_outside) {
        const Mesh c = control_mesh(U, T);
        const Input p = float_matrix(P, "P", {-1, c.U.map.cols()});
        interp::Embedding e = without_gil([&] { return interp::embed(c.U.map, c.T, p.map); });
        report_outside(e, p, max_outside);
        return e;
      },
      "U"_a, "T"_a, "P"_a, py::kw_only(), "max_outside"_a = py::none(),
      "Locates the dense rest points P (p, d) in the control mesh: U (n, d) rest vertices, T (m, d+1) "
      "elements (0-based). Returns an Embedding. Points outside are attached to the nearest element and "
      "warn (mbi.OutsideWarning); max_outside refuses those farther out than max_outside x the model size "
      "(the diagonal of P's bounding box), as mbi deform --max-outside.");

  m.def(
      "embedded_positions",
      [](const py::object& U, const py::object& T, const Embedding& e) {
        const Mesh c = control_mesh(U, T);
        return to_numpy(without_gil([&] { return interp::embedded_positions(c.U.map, c.T, e); }));
      },
      "U"_a, "T"_a, "embedding"_a, "The points an embedding stands for: sum_k bary[:, k] U[T[element, k]], (p, d).");

  m.def(
      "validate_mesh",
      [](const py::object& U, const py::object& T) {
        const Mesh c = control_mesh(U, T);
        without_gil([&] { interp::validate_mesh(c.U.map, c.T); });
      },
      "U"_a, "T"_a, "Raises mbi.Error unless (U, T) is a valid control mesh (finite, indices in range, no flat element).");

  m.def(
      "interior_faces",
      [](const py::object& T) {
        const Eigen::MatrixXi t = index_matrix(T, "T");
        return to_numpy(without_gil([&] { return interp::interior_faces(t); }));
      },
      "T"_a, "(F, d+2) int32: each interior face's d vertices, then its two elements.");

  m.def(
      "boundary_faces",
      [](const py::object& U, const py::object& T) {
        const Mesh c = control_mesh(U, T);
        return to_numpy(without_gil([&] { return interp::boundary_faces(c.U.map, c.T); }));
      },
      "U"_a, "T"_a, "(B, d) int32: the boundary faces, oriented outward.");

  py::class_<interp::HarmonicExtension>(
      m, "HarmonicExtension",
      "Moves a control mesh's free nodes with its fixed ones: the harmonic extension (P1 stiffness of the rest "
      "elements) of the fixed nodes' displacement; at rest the identity, affine motions kept.")
      .def(py::init([](const py::object& U, const py::object& T, const py::object& fixed) {
             const Mesh c = control_mesh(U, T);
             const std::vector<int> f = fixed.is_none() ? std::vector<int>{} : index_list(fixed, "fixed", c.U.map.rows());
             return without_gil([&] {
               Eigen::VectorXi nodes;
               if (fixed.is_none()) {  // the boundary
                 const Eigen::VectorXi on = interp::boundary_vertices(static_cast<int>(c.U.map.rows()), c.T);
                 nodes.resize(on.sum());
                 for (Eigen::Index v = 0, k = 0; v < on.size(); ++v)
                   if (on[v]) nodes[k++] = static_cast<int>(v);
               } else {
                 nodes = Eigen::Map<const Eigen::VectorXi>(f.data(), static_cast<Eigen::Index>(f.size()));
               }
               return interp::HarmonicExtension(c.U.map, c.T, nodes);
             });
           }),
           "U"_a, "T"_a, "fixed"_a = py::none(),
           "fixed: the nodes whose positions are given (indices or a boolean mask); None: the boundary's nodes.")
      .def(
          "apply",
          [](const interp::HarmonicExtension& h, const py::object& X) {
            const Eigen::Index n = h.free_nodes().size() + h.fixed_nodes().size();
            const Input x = float_matrix(X, "X");
            Eigen::MatrixXd Y = x.map;
            if (Y.rows() < n) throw interp::Error("X must have a row per node (" + std::to_string(n) + "), got " +
                                                 std::to_string(Y.rows()));
            without_gil([&] { h.apply(Y); });
            return to_numpy(std::move(Y));
          },
          "X"_a, "(n, d) float64: X with the free nodes' rows replaced (X is not modified).")
      .def_property_readonly("free_nodes", [](const interp::HarmonicExtension& h) { return node_array(h.free_nodes()); },
                             "ascending int32")
      .def_property_readonly("fixed_nodes", [](const interp::HarmonicExtension& h) { return node_array(h.fixed_nodes()); },
                             "ascending int32")
      .def_property_readonly("memory_bytes", &interp::HarmonicExtension::memory_bytes);

  m.def("default_alpha", &interp::default_alpha, "d"_a, "modified-BI's default alpha: 0.1 in 3D, 0.2 in 2D.");
  m.def("cholmod_available", &interp::cholmod_available, "True when this build factors with CHOLMOD.");
  m.def(
      "set_threads",
      &interp::set_threads,
      "n"_a,
      "Threads of every later call of the library (one pool for the process, shared by all Python "
      "threads), the calling one included; 0: the cores this process may run on. An object's own "
      "threads= limits it further.");
  m.def("threads", &interp::threads, "The thread count in force (>= 1).");
  m.def("threads_available", &interp::threads_available,
        "False in a build without the thread pool (CMake MBI_WITH_THREADS=OFF): every call is serial.");
}

}  // namespace mbi::python
