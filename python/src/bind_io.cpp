// Files: the readers and writers of mbi::io (surfaces with their attributes, control meshes,
// point lists, point caches, ParaView collections and control trajectories), numpy in and out.
// Every error names the file; it is an mbi.FileError (an mbi.Error and an OSError).
#include "bindings.hpp"

#include <mbi/io/io.hpp>

#include <filesystem>

namespace mbi::python {
namespace {

namespace fs = std::filesystem;
using io::SurfaceMesh;

fs::path path_arg(const py::handle& obj, const char* name) {
  try {
    return fs::path(py::module_::import("os").attr("fspath")(obj).cast<std::string>());
  } catch (const py::error_already_set&) {
    throw Error(std::string(name) + " must be a path (str or os.PathLike), got " + py::repr(obj).cast<std::string>());
  } catch (const py::cast_error&) {
    throw Error(std::string(name) + " must be a path (str or os.PathLike), got " + py::repr(obj).cast<std::string>());
  }
}

io::Encoding encoding_arg(const std::string& name) {
  if (name == "as_read") return io::Encoding::as_read;
  if (name == "ascii") return io::Encoding::ascii;
  if (name == "binary") return io::Encoding::binary;
  throw Error("encoding: unknown value \"" + name + "\" (expected one of: as_read, ascii, binary)");
}

Eigen::MatrixXd normals_arg(const py::object& N, Eigen::Index n) {
  if (N.is_none()) return {};
  return float_matrix(N, "N", {n, 3}).map;
}

SurfaceMesh make_surface(const py::object& V, const py::object& F, const py::object& N) {
  SurfaceMesh s;
  s.V = float_matrix(V, "V", {-1, 3}).map;
  if (!F.is_none()) s.F = index_matrix(F, "F", {-1, 3});
  s.N = normals_arg(N, s.V.rows());
  return s;
}

py::list polygons_of(const SurfaceMesh& s) {
  py::list out;
  for (const std::vector<int>& p : s.polygons) out.append(py::cast(p));
  return out;
}

void bind_surface(py::module_& m) {
  py::class_<SurfaceMesh>(m, "Surface",
      "A surface mesh as a file holds it (unpacks as V, F): V (n, 3), F (t, 3) triangles (polygons fan-triangulated), "
      "N (n, 3) unit normals or None, and what else the file held (OBJ texture coordinates, groups, "
      "materials, vertex colours; every PLY property; STL header), written back by write_surface to "
      "a file of the same format while the vertex count and faces stay.")
      .def(py::init(&make_surface), py::arg("V"), py::arg("F") = py::none(), py::arg("N") = py::none())
      .def_property("V", [](const SurfaceMesh& s) { return to_numpy(Eigen::Ref<const Eigen::MatrixXd>(s.V)); },
                    [](SurfaceMesh& s, const py::object& V) { s.V = float_matrix(V, "V", {-1, 3}).map; },
                    "(n, 3) vertex positions (a copy; assign to replace)")
      .def_property("F", [](const SurfaceMesh& s) { return to_numpy(s.F); },
                    [](SurfaceMesh& s, const py::object& F) {
                      s.F = index_matrix(F, "F", {-1, 3});
                      s.polygons.clear();  // the faces are these triangles now
                    }, "(t, 3) triangles, 0-based")
      .def_property("N", [](const SurfaceMesh& s) -> py::object {
                      if (s.N.size() == 0) return py::none();
                      return to_numpy(Eigen::Ref<const Eigen::MatrixXd>(s.N));
                    }, [](SurfaceMesh& s, const py::object& N) { s.N = normals_arg(N, s.V.rows()); },
                    "(n, 3) unit vertex normals, or None")
      .def("__iter__", [](const py::object& self) { return py::iter(py::make_tuple(self.attr("V"), self.attr("F"))); })
      .def_property_readonly("polygons", &polygons_of, "the faces as the file wrote them (lists of >= 3 indices)")
      .def_property_readonly("has_attributes", [](const SurfaceMesh& s) { return s.attributes != nullptr; },
                             "whether it keeps attributes of the file it was read from")
      .def("with_positions", [](const SurfaceMesh& s, const py::object& V, const py::object& N) {
        SurfaceMesh out = s;  // attributes are shared, not copied
        out.V = float_matrix(V, "V", {s.V.rows(), 3}).map;
        out.N = normals_arg(N, s.V.rows());
        return out;
      }, py::arg("V"), py::arg("N") = py::none(),
         "A copy with positions V (n, 3) and normals N (or none): a deformed frame of this mesh.")
      .def("__repr__", [](const SurfaceMesh& s) {
        return "Surface(" + std::to_string(s.V.rows()) + " vertices, " + std::to_string(s.F.rows()) + " triangles" +
               (s.attributes ? ", with the file's attributes)" : ")");
      });
  m.def("read_surface", [](const py::object& path) {
    const fs::path p = path_arg(path, "path");
    return without_gil([&] { return io::read_surface(p); });
  }, py::arg("path"), "Reads .obj, .off, .ply or .stl (by extension) into a Surface.");
  m.def("write_surface", [](const py::object& path, const py::object& mesh, const py::object& F, const py::object& N,
                            const std::string& encoding) {
    const fs::path p = path_arg(path, "path");
    const io::Encoding e = encoding_arg(encoding);
    SurfaceMesh s = py::isinstance<SurfaceMesh>(mesh) ? mesh.cast<SurfaceMesh>() : make_surface(mesh, F, py::none());
    if (!N.is_none()) s.N = normals_arg(N, s.V.rows());
    without_gil([&] { io::write_surface(p, s, e); });
  }, py::arg("path"), py::arg("mesh"), py::arg("F") = py::none(), py::kw_only(), py::arg("N") = py::none(),
     py::arg("encoding") = "as_read",
     "Writes a Surface (or V (n, 3) and F (t, 3)) to .obj, .off, .ply or .stl; encoding: as_read, ascii, binary.");
}

void bind_points(py::module_& m) {
  m.def("read_points", [](const py::object& path) {
    const fs::path p = path_arg(path, "path");
    return to_numpy(without_gil([&] { return io::read_points(p); }));
  }, py::arg("path"), "A point list (.txt, .xyz): (n, d).");
  m.def("write_points", [](const py::object& path, const py::object& P) {
    const fs::path p = path_arg(path, "path");
    const Input in = float_matrix(P, "P");
    without_gil([&] { io::write_points(p, in.map); });
  }, py::arg("path"), py::arg("P"));
}

void bind_control(py::module_& m) {
  py::class_<io::ControlMesh>(m, "ControlMesh", "A control mesh read from a file: U (n, d), T (m, d+1); unpacks as U, T.")
      .def_property_readonly("U", [](const io::ControlMesh& c) { return to_numpy(Eigen::Ref<const Eigen::MatrixXd>(c.U)); })
      .def_property_readonly("T", [](const io::ControlMesh& c) { return to_numpy(c.T); })
      .def_readonly("notes", &io::ControlMesh::notes, "what the reader changed or left out, one line each")
      .def_property_readonly("dim", &io::ControlMesh::dim)
      .def("__iter__", [](const py::object& self) {
        return py::iter(py::make_tuple(self.attr("U"), self.attr("T")));
      });
  m.def("read_control_mesh", [](const py::object& path) {
    const fs::path p = path_arg(path, "path");
    return without_gil([&] { return io::read_control_mesh(p); });
  }, py::arg("path"), "TetGen (.node/.ele or base name), Gmsh .msh, VTK .vtk or .vtu, by extension.");
  m.def("read_positions", [](const py::object& path) {
    const fs::path p = path_arg(path, "path");
    return to_numpy(without_gil([&] { return io::read_positions(p); }));
  }, py::arg("path"), "Node positions of a control mesh file (.node, .msh, .vtk, .vtu, or a point list): (n, d).");
  m.def("write_tetgen", [](const py::object& base, const py::object& U, const py::object& T) {
    const fs::path p = path_arg(base, "base");
    const Mesh c = control_mesh(U, T);
    without_gil([&] { io::write_tetgen(p, c.U.map, c.T); });
  }, py::arg("base"), py::arg("U"), py::arg("T"), "Writes BASE.node and BASE.ele.");
  m.def("write_vtk", [](const py::object& path, const py::object& U, const py::object& T, const py::object& vectors,
                        const std::string& name) {
    const fs::path p = path_arg(path, "path");
    const Mesh c = control_mesh(U, T);
    Eigen::MatrixXd v(0, 3);
    if (!vectors.is_none()) v = float_matrix(vectors, "point_vectors", {c.U.map.rows(), c.U.map.cols()}).map;
    without_gil([&] { io::write_vtk(p, c.U.map, c.T, v, name); });
  }, py::arg("path"), py::arg("U"), py::arg("T"), py::arg("point_vectors") = py::none(),
     py::arg("point_data") = "displacement", "Legacy VTK (ASCII), with optional per-point vectors (n, d).");
}

// Frames of equal shape (rows, cols) stacked into a new (frames, rows, cols) array.
py::array stacked(const std::vector<Eigen::MatrixXd>& frames, Eigen::Index rows, Eigen::Index cols) {
  const Eigen::Index f = static_cast<Eigen::Index>(frames.size());
  if (f == 0) return py::array_t<double>(std::vector<py::ssize_t>{0, rows, cols});
  Output out = float_output(py::none(), "frames", rows, cols, {f, true});
  for (Eigen::Index k = 0; k < f; ++k) out.map.middleRows(k * rows, rows) = frames[static_cast<size_t>(k)];
  return out.finish();
}

py::array cache_frames(const io::PointCache& c) {
  const Eigen::Index n = c.frames.empty() ? 0 : c.frames[0].rows();
  return stacked(c.frames, n, 3);
}

// frames of n points each; times: MDD's, one a frame (s); empty: frame k at k / rate
void write_cache(const fs::path& p, const Input& x, Eigen::Index frames, Eigen::Index n, float start, float rate,
                 std::vector<float> t) {
  const std::string ext = io::lower_extension(p);
  if (ext == ".pc2") {
    io::Pc2Writer w(p, static_cast<int>(n), start, rate);
    for (Eigen::Index k = 0; k < frames; ++k) w.append(x.map.middleRows(k * n, n));
    return w.finish();
  }
  if (ext != ".mdd") throw io::Error(p.string() + ": a point cache is .pc2 or .mdd");
  if (t.empty())
    for (Eigen::Index k = 0; k < frames; ++k) t.push_back(static_cast<float>(k) / rate);
  if (static_cast<Eigen::Index>(t.size()) != frames)
    throw Error("times must have one entry a frame (" + std::to_string(frames) + "), got " + std::to_string(t.size()));
  io::MddWriter w(p, static_cast<int>(n), t);
  for (Eigen::Index k = 0; k < frames; ++k) w.append(x.map.middleRows(k * n, n));
  w.finish();
}

void bind_caches(py::module_& m) {
  py::class_<io::PointCache>(m, "PointCache", "A PC2 or MDD point cache read back.")
      .def_property_readonly("frames", &cache_frames, "(frames, n, 3) positions")
      .def_readonly("start_frame", &io::PointCache::start_frame, "PC2's start frame")
      .def_readonly("sample_rate", &io::PointCache::sample_rate, "PC2's frames per sample")
      .def_readonly("times", &io::PointCache::times, "MDD: each frame's time, s; PC2: []");
  m.def("read_point_cache", [](const py::object& path) {
    const fs::path p = path_arg(path, "path");
    return without_gil([&] {
      if (io::lower_extension(p) == ".mdd") return io::read_mdd(p);
      if (io::lower_extension(p) == ".pc2") return io::read_pc2(p);
      throw io::Error(p.string() + ": a point cache is .pc2 or .mdd");
    });
  }, py::arg("path"), "Reads a .pc2 or .mdd point cache.");
  m.def("write_point_cache", [](const py::object& path, const py::object& frames, float start_frame, float sample_rate,
                                const py::object& times) {
    const fs::path p = path_arg(path, "path");
    Frames f;
    const Input x = float_batch(frames, "frames", {-1, 3}, f);
    if (!f.batch) throw Error("frames must have shape (frames, n, 3)");
    std::vector<float> t;
    if (!times.is_none()) t = times.cast<std::vector<float>>();
    const Eigen::Index n = x.source.shape(1);
    without_gil([&] { write_cache(p, x, f.count, n, start_frame, sample_rate, std::move(t)); });
  }, py::arg("path"), py::arg("frames"), py::kw_only(), py::arg("start_frame") = 0.0f, py::arg("sample_rate") = 1.0f,
     py::arg("times") = py::none(),
     "Writes (frames, n, 3) float32 positions to .pc2 (start_frame, sample_rate) or .mdd (times, s).");
  m.def("read_pvd", [](const py::object& path) {
    const fs::path p = path_arg(path, "path");
    py::list out;
    for (const io::PvdEntry& e : io::read_pvd(p)) out.append(py::make_tuple(e.time, e.file.string()));
    return out;
  }, py::arg("path"), "A ParaView collection: [(time, file)] sorted by time (files not opened).");
  m.def("read_trajectory", [](const py::object& path) {
    const std::string spec = path_arg(path, "spec").string();
    auto [frames, times] = without_gil([&] {
      io::Trajectory t(spec);
      std::vector<Eigen::MatrixXd> list;
      for (int k = 0; k < t.frames(); ++k) {
        list.push_back(t.read(k));
        if (list.back().rows() != list[0].rows() || list.back().cols() != list[0].cols())
          throw io::Error(t.where(k) + ": not the shape of the first frame");
      }
      return std::make_pair(std::move(list), t.times());
    });
    const Eigen::Index rows = frames.empty() ? 0 : frames[0].rows(), cols = frames.empty() ? 3 : frames[0].cols();
    return py::make_tuple(stacked(frames, rows, cols), py::cast(times));
  }, py::arg("spec"),
     "Control positions over time (.pc2, .mdd, .pvd, a printf pattern or a glob): ((frames, n, d) array, times in s "
     "or [])");
}

}  // namespace

void bind_io(py::module_& m) {
  bind_surface(m);
  bind_points(m);
  bind_control(m);
  bind_caches(m);
}

}  // namespace mbi::python
