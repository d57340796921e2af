// The methods' M and Bezier points: ModifiedBI, Phong, bezier_bi / bezier_points, and the
// discontinuity metrics (paper Table 2).
#include "bindings.hpp"

#include <mbi/interp/metrics.hpp>
#include <mbi/interp/modified_bi.hpp>
#include <mbi/interp/phong.hpp>

#include <pybind11/stl.h>

namespace mbi::python {
namespace {

using interp::ModifiedBI;
using interp::Phong;
using Solver = Guarded<ModifiedBI>;

std::unique_ptr<Solver> make_solver(const py::object& U, const py::object& T, std::optional<double> alpha, double beta,
                                    bool pin_boundary, const std::string& solve_path, const std::string& factorization,
                                    const py::object& max_memory) {
  const Mesh c = control_mesh(U, T);
  interp::Options o;
  o.alpha = alpha;
  o.beta = beta;
  o.pin_boundary = pin_boundary;
  o.solve_path = interp::kSolvePathNames.parse(solve_path, "solve_path");
  o.factorization = interp::kFactorizationNames.parse(factorization, "factorization");
  o.max_memory = max_memory_arg(max_memory);
  return without_gil([&] { return std::make_unique<Solver>(c.U.map, c.T, o); });
}

// A pose X of s's control mesh, (n, d).
Input pose(const py::handle& X, int n, int d) { return float_matrix(X, "X", {n, d}); }
// Per-vertex matrices M ((n d), d).
Input vertex_matrices(const py::handle& M, const char* name, int n, int d) {
  return float_matrix(M, name, {static_cast<Eigen::Index>(n) * d, d});
}

template <class Cls>
void solver_properties(Cls& c) {
  auto get = [](auto f) { return [f](Solver& s) { return s.run([&](const ModifiedBI& b) { return f(b); }); }; };
  c.def_property_readonly("dim", get([](const ModifiedBI& b) { return b.dim(); }), "d: 2 or 3")
      .def_property_readonly("vertices", get([](const ModifiedBI& b) { return b.vertices(); }), "n")
      .def_property_readonly("elements", get([](const ModifiedBI& b) { return b.elements(); }), "m")
      .def_property_readonly("alpha", get([](const ModifiedBI& b) { return b.alpha(); }), "weight of E_vibr")
      .def_property_readonly("beta", get([](const ModifiedBI& b) { return b.beta(); }), "weight of E_disc")
      .def_property_readonly("pin_boundary", get([](const ModifiedBI& b) { return b.pin_boundary(); }))
      .def_property_readonly("null_space_dim", get([](const ModifiedBI& b) { return b.null_space_dim(); }),
                             "gauge null vectors removed per component")
      .def_property_readonly("unknowns", get([](const ModifiedBI& b) { return b.unknowns(); }),
                             "scalar unknowns per component after pinning")
      .def_property_readonly("dense_operator", get([](const ModifiedBI& b) { return b.dense_operator(); }),
                             "True when solve() is one dense product")
      .def_property_readonly("factorization", get([](const ModifiedBI& b) { return b.factorization(); }))
      .def_property_readonly("factor_nonzeros", get([](const ModifiedBI& b) { return b.factor_nonzeros(); }))
      .def_property_readonly("factor_stored_values", get([](const ModifiedBI& b) { return b.factor_stored_values(); }),
                             "values the factor stores (supernodal blocks whole): what a solve reads twice")
      .def_property_readonly("factor_index_bytes", get([](const ModifiedBI& b) { return b.factor_index_bytes(); }),
                             "bytes of the factor's index arrays that a solve reads")
      .def_property_readonly("memory_bytes", get([](const ModifiedBI& b) { return b.memory_bytes(); }),
                             "bytes the precompute keeps");
}

void bind_modified_bi(py::module_& m) {
  using namespace pybind11::literals;
  py::class_<Solver> c(m, "ModifiedBI",
                       "Modified-BI's precompute for one rest control mesh (assembly, gauge, sparse Cholesky "
                       "factor); solve() gives M per pose.");
  c.def(py::init(&make_solver), "U"_a, "T"_a, py::kw_only(), "alpha"_a = py::none(), "beta"_a = 0.0,
        "pin_boundary"_a = false, "solve_path"_a = "automatic", "factorization"_a = "automatic", "max_memory"_a = py::none(),
        "U (n, d) rest vertices, T (m, d+1) elements. alpha: weight of E_vibr (None: 0.1 in 3D, 0.2 in 2D); "
        "beta: weight of E_disc (0: automatic); pin_boundary: M = 0 on boundary vertices; solve_path: "
        "automatic, sparse, dense or iterative (automatic takes it when the factor's estimated peak exceeds "
        "max_memory: bytes or a size such as '8G'; None: the memory available); factorization: automatic, eigen or "
        "cholmod.");
  c.def(
      "solve",
      [](Solver& s, const py::object& X, const py::object& out) {
        const int n = s.object.vertices(), d = s.object.dim();
        const Input x = pose(X, n, d);
        return result(out, static_cast<Eigen::Index>(n) * d, d, {&x}, [&](interp::MatrixOut M) {
          s.run([&](const ModifiedBI& b) { b.solve(kept_columns(x), M); });
        });
      },
      "X"_a, py::kw_only(), "out"_a = py::none(),
      "M ((n d), d) for the deformed control positions X (n, d): rows [i d, i d + d) hold M_i. "
      "out: a float64 array of that shape to write into.");
  c.def(
      "solve_transpose",
      [](Solver& s, const py::object& G) {
        const Input g = vertex_matrices(G, "G", s.object.vertices(), s.object.dim());
        return c_order(s.run([&](const ModifiedBI& b) { return b.solve_transpose(g.map); }));
      },
      "G"_a, "The transpose of solve() (linear in X): dL/dX (n, d) from G = dL/dM ((n d), d).");
  c.def(
      "bezier",
      [](Solver& s, const py::object& X, const py::object& M, const py::object& out) {
        const int n = s.object.vertices(), d = s.object.dim();
        const Input x = pose(X, n, d), mm = vertex_matrices(M, "M", n, d);
        const int K = (d + 1) * (d + 2) / 2;
        return result(out, static_cast<Eigen::Index>(s.object.elements()) * K, d, {&x, &mm}, [&](interp::MatrixOut B) {
          s.run([&](const ModifiedBI& b) {
            interp::bezier_points(b.rest_positions(), b.elements_matrix(), kept_columns(x), mm.map, B);
          });
        });
      },
      "X"_a, "M"_a, py::kw_only(), "out"_a = py::none(),
      "Element Bezier points ((m K), d), K = (d+1)(d+2)/2: per element its d+1 vertices, then its edge points.");
  c.def(
      "set_alpha", [](Solver& s, double alpha) { s.run([&](ModifiedBI& b) { b.set_alpha(alpha); }); }, "alpha"_a,
      "Changes alpha (> 0) and refactors.");
  solver_properties(c);
}

void bind_phong(py::module_& m) {
  using namespace pybind11::literals;
  py::class_<Phong>(m, "Phong", "Phong deformation's closed-form M (James 2020): M_i = F_i / 2.")
      .def(py::init([](const py::object& U, const py::object& T) {
             const Mesh c = control_mesh(U, T);
             return without_gil([&] { return Phong(c.U.map, c.T); });
           }),
           "U"_a, "T"_a, "U (n, d) rest vertices, T (m, d+1) elements.")
      .def(
          "M",
          [](const Phong& p, const py::object& X, const py::object& out) {
            const Input x = pose(X, p.vertices(), p.dim());
            return result(out, static_cast<Eigen::Index>(p.vertices()) * p.dim(), p.dim(), {&x},
                          [&](interp::MatrixOut M) { without_gil([&] { p.M(kept_columns(x), M); }); });
          },
          "X"_a, py::kw_only(), "out"_a = py::none(), "M ((n d), d) at pose X (n, d).")
      .def(
          "M_transpose",
          [](const Phong& p, const py::object& G) {
            const Input g = vertex_matrices(G, "G", p.vertices(), p.dim());
            return c_order(without_gil([&] { return p.M_transpose(g.map); }));
          },
          "G"_a, "The transpose of M() (linear in X): dL/dX (n, d) from G = dL/dM ((n d), d).")
      .def(
          "element_gradients",
          [](const Phong& p, const py::object& X) {
            const Input x = pose(X, p.vertices(), p.dim());
            return to_numpy(without_gil([&] { return p.element_gradients(x.map); }));
          },
          "X"_a, "F_e = D_s D_m^-1 per element, ((m d), d).")
      .def(
          "vertex_gradients",
          [](const Phong& p, const py::object& X) {
            const Input x = pose(X, p.vertices(), p.dim());
            return to_numpy(without_gil([&] { return p.vertex_gradients(x.map); }));
          },
          "X"_a, "F_i per vertex, ((n d), d).")
      .def_property_readonly("dim", &Phong::dim)
      .def_property_readonly("vertices", &Phong::vertices)
      .def_property_readonly("elements", &Phong::elements)
      .def_property_readonly("fallback_vertices", &Phong::fallback_vertices);
}

void bind_bezier(py::module_& m) {
  using namespace pybind11::literals;
  m.def(
      "bezier_bi",
      [](const py::object& X, const py::object& T) {
        const Input x = float_matrix(X, "X");
        const Eigen::MatrixXi t = index_matrix(T, "T", {-1, x.map.cols() + 1});
        return to_numpy(without_gil([&] { return interp::bezier_bi(x.map, t); }));
      },
      "X"_a, "T"_a, "Bezier points ((m K), d) of plain BI (M = 0) at pose X (n, d).");
  m.def(
      "bezier_points",
      [](const py::object& U, const py::object& T, const py::object& X, const py::object& M) {
        const Mesh c = control_mesh(U, T);
        const int n = static_cast<int>(c.U.map.rows()), d = static_cast<int>(c.U.map.cols());
        const Input x = pose(X, n, d), mm = vertex_matrices(M, "M", n, d);
        return to_numpy(without_gil([&] { return interp::bezier_points(c.U.map, c.T, x.map, mm.map); }));
      },
      "U"_a, "T"_a, "X"_a, "M"_a, "Bezier points ((m K), d) for any M ((n d), d) at pose X (n, d).");
}

void bind_metrics(py::module_& m) {
  using namespace pybind11::literals;
  py::class_<interp::Summary>(m, "Summary", "mean, std (population) and max of a per-face quantity")
      .def_readonly("mean", &interp::Summary::mean)
      .def_readonly("std", &interp::Summary::std)
      .def_readonly("max", &interp::Summary::max)
      .def("__repr__", [](const interp::Summary& s) {
        return "<mbi.Summary mean " + std::to_string(s.mean) + ", std " + std::to_string(s.std) + ", max " +
               std::to_string(s.max) + ">";
      });
  py::class_<interp::DiscontinuityTable>(m, "DiscontinuityTable", "Paper Table 2 for one pose")
      .def_readonly("bi", &interp::DiscontinuityTable::bi)
      .def_readonly("modified_bi", &interp::DiscontinuityTable::modified_bi)
      .def_readonly("ratio", &interp::DiscontinuityTable::ratio, "bi / modified_bi, field by field")
      .def_readonly("phong", &interp::DiscontinuityTable::phong, "Phong's column, or None")
      .def_readonly("phong_ratio", &interp::DiscontinuityTable::phong_ratio, "bi / phong")
      .def_readonly("e_vibr", &interp::DiscontinuityTable::e_vibr)
      .def_readonly("e_disc", &interp::DiscontinuityTable::e_disc)
      .def_readonly("e_total", &interp::DiscontinuityTable::e_total)
      .def_readonly("faces", &interp::DiscontinuityTable::faces);
  m.def(
      "discontinuity_table",
      [](Solver& s, const py::object& X, const py::object& M, const py::object& M_phong) {
        const int n = s.object.vertices(), d = s.object.dim();
        const Input x = pose(X, n, d), mm = vertex_matrices(M, "M", n, d);
        if (M_phong.is_none())
          return s.run([&](const ModifiedBI& b) { return interp::discontinuity_table(b, x.map, mm.map); });
        const Input mp = vertex_matrices(M_phong, "M_phong", n, d);
        return s.run([&](const ModifiedBI& b) { return interp::discontinuity_table(b, x.map, mm.map, mp.map); });
      },
      "solver"_a, "X"_a, "M"_a, "M_phong"_a = py::none(),
      "Face discontinuity of BI against modified-BI's M (and Phong's M_phong when given) at pose X.");
  m.def(
      "face_discontinuity",
      [](const py::object& U, const py::object& T, const py::object& X, const py::object& M) {
        const Mesh c = control_mesh(U, T);
        const int n = static_cast<int>(c.U.map.rows()), d = static_cast<int>(c.U.map.cols());
        const Input x = pose(X, n, d), mm = vertex_matrices(M, "M", n, d);
        return to_numpy_vector(without_gil([&] { return interp::face_discontinuity(c.U.map, c.T, x.map, mm.map); }));
      },
      "U"_a, "T"_a, "X"_a, "M"_a, "Per interior face (interior_faces order) the gradient jump energy E_F, (F,).");
}

}  // namespace

void bind_methods(py::module_& m) {
  bind_modified_bi(m);
  bind_phong(m);
  bind_bezier(m);
  bind_metrics(m);
}

}  // namespace mbi::python
