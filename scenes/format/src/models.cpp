// load_models: the dense model and the control mesh of a scene, in one dimension.
#include "model_files.hpp"

#include <mbi/generate/cage.hpp>
#include <mbi/generate/procedural.hpp>
#include <mbi/generate/subdivide.hpp>
#include <mbi/scenes/limits.hpp>
#include <mbi/scenes/models.hpp>

#include <algorithm>

namespace fs = std::filesystem;

namespace mbi::scenes {
namespace {

// Loop subdivision when the scene asks for it.
void subdivide(const Scene& sc, const DenseSpec& d, io::SurfaceMesh& s) {
  if (d.subdivide == 0) return;
  if (s.V.cols() != 3) throw Error(sc.file.string() + ": dense.subdivide: only for 3D surfaces");
  generate::loop_subdivide(s, d.subdivide);
  s.N.resize(0, 0);  // the file's normals and attributes belong to the unrefined mesh
  s.attributes.reset();
}

// The dense model: --mesh, the scene's file or a built-in.
void load_dense(const Scene& sc, const fs::path& mesh_override, SceneModels& m) {
  if (!mesh_override.empty()) {
    m.dense = read_surface(sc, mesh_override, "--mesh");
    m.dense_name = mesh_override.string();
  } else if (!sc.dense.path.empty()) {
    const fs::path p = resolve_path(sc, sc.dense.path);
    m.dense = read_surface(sc, p, "dense.path");
    m.dense_name = p.string();
  } else if (sc.dense.builtin == DenseBuiltin::PaperBar) {
    generate::paper_bar_surface(m.dense.V, m.dense.F);
    m.dense_name = "built-in paper bar";
  } else if (sc.dense.builtin == DenseBuiltin::Cylinder) {
    generate::cylinder_surface(0.5, 4.0, 96, 192, 12, m.dense.V, m.dense.F);
    m.dense_name = "built-in cylinder";
  } else if (sc.dense.builtin == DenseBuiltin::BumpySphere) {
    generate::bumpy_sphere(1.0, 205, 0.05, m.dense.V, m.dense.F);
    m.dense_name = "built-in bumpy sphere";
  } else if (sc.dense.builtin == DenseBuiltin::ImageGrid) {
    io::Image img = sc.dense.image.empty() ? generate::test_pattern(512, 384)
                                           : read_image(sc, resolve_path(sc, sc.dense.image));
    const int longer = std::max(img.width, img.height);
    const int gx = std::max(2, sc.dense.grid * img.width / longer);
    const int gy = std::max(2, sc.dense.grid * img.height / longer);
    generate::grid_2d(img.width, img.height, gx, gy, m.dense.V, m.dense.F);
    m.dense_name =
        sc.dense.image.empty() ? "built-in test pattern" : resolve_path(sc, sc.dense.image).string();
    m.image = std::move(img);
  }
}

// [[dense]]: the other models' files joined after the first (deform_parts in the app does the
// same for mbi deform); each part keeps its own surface for its output.
void add_more_dense(const Scene& sc, SceneModels& m) {
  m.dense_parts.push_back({m.dense_name, 0, m.dense.V.rows(), m.dense});
  for (const DenseSpec& d : sc.more_dense) {
    const fs::path p = resolve_path(sc, d.path);
    io::SurfaceMesh s = read_surface(sc, p, "dense.path");
    subdivide(sc, d, s);
    if (s.V.rows() == 0) throw Error(p.string() + ": the dense model has no vertices");
    m.dense_parts.push_back({p.string(), m.dense_parts.back().first + m.dense_parts.back().rows, s.V.rows(), s});
  }
  io::SurfaceMesh joined;
  joined.V.resize(m.dense_parts.back().first + m.dense_parts.back().rows, 3);
  Eigen::Index faces = 0;
  bool normals = true;
  for (const DensePart& part : m.dense_parts) {
    faces += part.surface.F.rows();
    normals = normals && part.surface.N.rows() == part.rows;
  }
  joined.F.resize(faces, 3);
  if (normals) joined.N.resize(joined.V.rows(), 3);
  faces = 0;
  m.dense_name.clear();
  for (const DensePart& part : m.dense_parts) {
    joined.V.middleRows(part.first, part.rows) = part.surface.V;
    if (normals) joined.N.middleRows(part.first, part.rows) = part.surface.N;
    joined.F.middleRows(faces, part.surface.F.rows()) = part.surface.F.array() + static_cast<int>(part.first);
    faces += part.surface.F.rows();
    m.dense_name += (m.dense_name.empty() ? "" : ", ") + part.name;
  }
  m.dense = std::move(joined);
}

// A flat 3-coordinate model is 2D (as in mbi cage and mbi deform): z is dropped and kept in
// flat_z, unless --force-3d or a 3D control mesh file says otherwise. Control meshes that can
// only be 3D are refused here, naming the way out.
void drop_flat_z(const Scene& sc, bool force_3d, const std::optional<io::ControlMesh>& from_file,
                 SceneModels& m) {
  if (!generate::is_planar(m.dense.V) || force_3d || (from_file && from_file->dim() == 3)) return;
  const std::string flat = m.dense_name + ": the model is flat (every z = " + format_num(m.dense.V(0, 2)) +
                           "), a 2D input";
  if (sc.control.builtin == ControlBuiltin::Box && sc.control.path.empty())
    throw Error(flat + ", but control.builtin = \"" + builtin_name(sc.control.builtin) +
                     "\" is 3D: use \"" + builtin_name(ControlBuiltin::Grid2D) +
                     "\" or generate_vertices, or --force-3d");
  if (sc.control.path.empty() && sc.control.builtin == ControlBuiltin::None &&
      sc.control.mesher == generate::Mesher::TetGen)
    throw Error(flat + "; control.mesher = \"" + generate::mesher_name(sc.control.mesher) +
                     "\" makes tetrahedra only: use the voxel mesher for a 2D triangle cage, or "
                     "--force-3d");
  m.flat_z = m.dense.V(0, 2);
  m.dense.V.conservativeResize(Eigen::NoChange, 2);
  m.dense.N.resize(0, 0);
}

Eigen::MatrixXd padded_box_control(const Eigen::MatrixXd& V, const Eigen::Vector3i& cells,
                                   Eigen::MatrixXi& T) {
  Eigen::Vector3d lo = V.colwise().minCoeff().transpose(), hi = V.colwise().maxCoeff().transpose();
  const Eigen::Vector3d pad = 1e-3 * (hi - lo).cwiseMax(1e-9);
  Eigen::MatrixXd U;
  generate::box_tets(lo - pad, hi + pad, cells, U, T);
  return U;
}

// control.generate_vertices: a cage generated around the dense model.
void generate_control(const Scene& sc, bool force_3d, SceneModels& m) {
  generate::CageOptions co;
  co.target_vertices = sc.control.generate_vertices;
  co.mesher = sc.control.mesher;
  co.force_3d = force_3d;
  Eigen::MatrixXd V3 = Eigen::MatrixXd::Zero(m.dense.V.rows(), 3);  // a 2D model: z = 0
  V3.leftCols(m.dense.V.cols()) = m.dense.V;
  generate::CageResult cage;
  try {
    cage = generate::make_cage(V3, m.dense.F, co);
  } catch (const generate::Error& e) {  // named by the scene key that asked for it
    throw Error(sc.file.string() + ": control.generate_vertices = " +
                     std::to_string(co.target_vertices) + ": " + e.what());
  }
  m.U = cage.U;
  m.T = cage.T;
  m.generate_seconds = cage.seconds;
  m.control_name = std::string("generated control mesh (") + generate::mesher_name(cage.mesher) + ", " +
                   std::to_string(cage.U.rows()) + " vertices, min dihedral " +
                   format_num(cage.min_dihedral_deg) + " deg)";
}

// The control mesh: the scene's file, a built-in, or generated.
void load_control(const Scene& sc, bool force_3d, std::optional<io::ControlMesh> from_file, SceneModels& m) {
  const std::string where = sc.file.string();
  const std::string builtin = std::string("control.builtin = \"") + builtin_name(sc.control.builtin) + "\"";
  const bool two_d = m.dense.V.cols() == 2;
  if (from_file) {
    m.U = std::move(from_file->U);
    m.T = std::move(from_file->T);
    m.control_name = resolve_path(sc, sc.control.path).string();
  } else if (sc.control.builtin == ControlBuiltin::PaperBar) {
    generate::paper_bar_control(m.U, m.T);
    m.control_name = "built-in paper bar control (35 vertices)";
  } else if (sc.control.builtin == ControlBuiltin::Box) {
    if (two_d)
      throw Error(where + ": " + builtin + " is 3D; use \"" +
                       builtin_name(ControlBuiltin::Grid2D) + "\"");
    m.U = padded_box_control(m.dense.V, sc.control.cells, m.T);
    m.control_name = "built-in box control";
  } else if (sc.control.builtin == ControlBuiltin::Grid2D) {
    if (!two_d) throw Error(where + ": " + builtin + " needs a 2D dense model");
    const Eigen::Vector2d lo = m.dense.V.colwise().minCoeff().transpose();
    const Eigen::Vector2d hi = m.dense.V.colwise().maxCoeff().transpose();
    Eigen::MatrixXd G;
    generate::grid_2d(hi.x() - lo.x(), hi.y() - lo.y(), sc.control.cells.x(), sc.control.cells.y(), G, m.T);
    m.U = G.rowwise() + lo.transpose();
    m.control_name = "built-in 2D grid control";
  } else {
    generate_control(sc, force_3d, m);
  }
}

// The models around the dense model m.dense: Loop-subdivided when the scene asks, joined with
// the scene's other dense models (`more`), in their control mesh.
SceneModels with_control(const Scene& sc, SceneModels m, bool more, bool force_3d) {
  subdivide(sc, sc.dense, m.dense);
  if (m.dense.V.rows() == 0) throw Error(m.dense_name + ": the dense model has no vertices");
  if (more && !sc.more_dense.empty()) add_more_dense(sc, m);
  std::optional<io::ControlMesh> from_file;
  if (!sc.control.path.empty()) from_file = read_control_mesh(sc, resolve_path(sc, sc.control.path));
  drop_flat_z(sc, force_3d, from_file, m);
  load_control(sc, force_3d, std::move(from_file), m);
  const std::string where = sc.file.string();
  if (m.U.cols() != m.dense.V.cols())
    throw Error(where + ": the control mesh is " + std::to_string(m.U.cols()) +
                     "D but the dense model is " + std::to_string(m.dense.V.cols()) + "D");
  // before the embedding, the assembly and the factorisation allocate anything
  check_run_size(where, m.dense.V.rows(), m.U, m.T, {}, true);
  return m;
}

}  // namespace

SceneModels load_models(const Scene& sc, const fs::path& mesh_override, bool force_3d) {
  SceneModels m;
  load_dense(sc, mesh_override, m);
  return with_control(sc, std::move(m), mesh_override.empty(), force_3d);
}

SceneModels load_models(const Scene& sc, io::SurfaceMesh dense, const std::string& name, bool force_3d) {
  SceneModels m;
  m.dense = std::move(dense);
  m.dense_name = name;
  return with_control(sc, std::move(m), false, force_3d);
}

}  // namespace mbi::scenes
