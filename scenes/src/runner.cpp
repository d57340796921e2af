#include <mbi/generate/cage.hpp>
#include <mbi/generate/procedural.hpp>
#include <mbi/generate/subdivide.hpp>
#include <mbi/gpu/renderer.hpp>
#include <mbi/interp.hpp>
#include <mbi/io/atomic_file.hpp>
#include <mbi/io/parse.hpp>
#include <mbi/raster/raster.hpp>
#include <mbi/scenes/limits.hpp>
#include <mbi/scenes/report.hpp>
#include <mbi/scenes/runner.hpp>
#include <mbi/sim/simulator.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <regex>

namespace fs = std::filesystem;

namespace mbi::scenes {
namespace {

using generate::box_tets;
using generate::grid_2d;
using io::Image;

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

fs::path resolve(const Scene& sc, const fs::path& p) {
  if (p.is_absolute()) return p;
  return sc.file.parent_path() / p;
}


Eigen::MatrixXd padded_box_control(const Eigen::MatrixXd& V, const Eigen::Vector3i& cells,
                                   Eigen::MatrixXi& T) {
  Eigen::Vector3d lo = V.colwise().minCoeff().transpose(), hi = V.colwise().maxCoeff().transpose();
  const Eigen::Vector3d pad = 1e-3 * (hi - lo).cwiseMax(1e-9);
  Eigen::MatrixXd U;
  box_tets(lo - pad, hi + pad, cells, U, T);
  return U;
}

std::string format_num(double x) {
  char b[64];
  std::snprintf(b, sizeof b, "%.3g", x);
  return b;
}

}  // namespace

SceneModels load_models(const Scene& sc, const fs::path& mesh_override, bool force_3d) {
  SceneModels m;
  const std::string where = sc.file.string();
  // ------------------------------------------------------------------ dense
  if (!mesh_override.empty()) {
    m.dense = io::read_surface(mesh_override);
    m.dense_name = mesh_override.string();
  } else if (!sc.dense.path.empty()) {
    const fs::path p = resolve(sc, sc.dense.path);
    m.dense = io::read_surface(p);
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
    Image img = sc.dense.image.empty() ? generate::test_pattern(512, 384)
                                       : io::read_png(resolve(sc, sc.dense.image));
    const int longer = std::max(img.width, img.height);
    const int gx = std::max(2, sc.dense.grid * img.width / longer);
    const int gy = std::max(2, sc.dense.grid * img.height / longer);
    grid_2d(img.width, img.height, gx, gy, m.dense.V, m.dense.F);
    m.dense_name = sc.dense.image.empty() ? "built-in test pattern" : resolve(sc, sc.dense.image).string();
    m.image = std::move(img);
  }
  if (sc.dense.subdivide > 0) {
    if (m.dense.V.cols() != 3) throw SceneError(where + ": dense.subdivide: only for 3D surfaces");
    generate::loop_subdivide(m.dense, sc.dense.subdivide);
    m.dense.N.resize(0, 0);  // the file's normals and attributes belong to the unrefined mesh
    m.dense.attributes.reset();
  }
  if (m.dense.V.rows() == 0) throw SceneError(m.dense_name + ": the dense model has no vertices");

  // ------------------------------------------------------------------ control
  std::optional<io::ControlMesh> from_file;
  if (!sc.control.path.empty()) from_file = io::read_control_mesh(resolve(sc, sc.control.path));
  // a flat 3-coordinate model is 2D (as in mbi cage and mbi deform) unless --force-3d or a 3D
  // control mesh file says otherwise
  const bool flat = generate::is_planar(m.dense.V);
  if (flat && !force_3d && !(from_file && from_file->dim() == 3)) {
    if (sc.control.builtin == ControlBuiltin::Box && sc.control.path.empty())
      throw SceneError(m.dense_name + ": the model is flat (every z = " + format_num(m.dense.V(0, 2)) +
                       "), a 2D input, but control.builtin = \"box\" is 3D: use \"grid-2d\" or "
                       "generate_vertices, or --force-3d");
    if (sc.control.path.empty() && sc.control.builtin == ControlBuiltin::None &&
        sc.control.mesher == generate::Mesher::TetGen)
      throw SceneError(m.dense_name + ": the model is flat (every z = " + format_num(m.dense.V(0, 2)) +
                       "), a 2D input; control.mesher = \"tetgen\" makes tetrahedra only: use the "
                       "voxel mesher for a 2D triangle cage, or --force-3d");
    m.flat_z = m.dense.V(0, 2);
    m.dense.V.conservativeResize(Eigen::NoChange, 2);
    m.dense.N.resize(0, 0);
  }
  const bool two_d = m.dense.V.cols() == 2;
  if (from_file) {
    m.U = from_file->U;
    m.T = from_file->T;
    m.control_name = resolve(sc, sc.control.path).string();
  } else if (sc.control.builtin == ControlBuiltin::PaperBar) {
    generate::paper_bar_control(m.U, m.T);
    m.control_name = "built-in paper bar control (35 vertices)";
  } else if (sc.control.builtin == ControlBuiltin::Box) {
    if (two_d) throw SceneError(where + ": control.builtin = \"box\" is 3D; use \"grid-2d\"");
    m.U = padded_box_control(m.dense.V, sc.control.cells, m.T);
    m.control_name = "built-in box control";
  } else if (sc.control.builtin == ControlBuiltin::Grid2D) {
    if (!two_d) throw SceneError(where + ": control.builtin = \"grid-2d\" needs a 2D dense model");
    const Eigen::Vector2d lo = m.dense.V.colwise().minCoeff().transpose();
    const Eigen::Vector2d hi = m.dense.V.colwise().maxCoeff().transpose();
    Eigen::MatrixXd G;
    grid_2d(hi.x() - lo.x(), hi.y() - lo.y(), sc.control.cells.x(), sc.control.cells.y(), G, m.T);
    m.U = G.rowwise() + lo.transpose();
    m.control_name = "built-in 2D grid control";
  } else {
    generate::CageOptions co;
    co.target_vertices = sc.control.generate_vertices;
    co.mesher = sc.control.mesher;
    co.force_3d = force_3d;
    Eigen::MatrixXd V3 = Eigen::MatrixXd::Zero(m.dense.V.rows(), 3);  // a 2D model: z = 0
    V3.leftCols(m.dense.V.cols()) = m.dense.V;
    generate::CageResult cage;
    try {
      cage = generate::make_cage(V3, m.dense.F, co);
    } catch (const generate::CageError& e) {  // the scene key that asked for it, without "make_cage: "
      const std::string w = e.what(), who = "make_cage: ";
      throw SceneError(where + ": control.generate_vertices = " + std::to_string(co.target_vertices) +
                       ": " + (w.rfind(who, 0) == 0 ? w.substr(who.size()) : w));
    }
    m.U = cage.U;
    m.T = cage.T;
    m.generate_seconds = cage.seconds;
    m.control_name = std::string("generated control mesh (") + generate::mesher_name(cage.mesher) + ", " +
                     std::to_string(cage.U.rows()) + " vertices, min dihedral " +
                     format_num(cage.min_dihedral_deg) + " deg)";
  }
  if (m.U.cols() != m.dense.V.cols())
    throw SceneError(where + ": the control mesh is " + std::to_string(m.U.cols()) +
                     "D but the dense model is " + std::to_string(m.dense.V.cols()) + "D");
  // before the embedding, the assembly and the factorisation allocate anything
  check_run_size(where, m.dense.V.rows(), m.U.rows(), m.T.rows(), static_cast<int>(m.U.cols()));
  return m;
}

namespace {

// Linear interpolation of drag keyframes at frame f (held before the first and after the last).
Eigen::Vector3d key_at(const DragSpec& d, double f) {
  if (f <= d.keys.front().first) return d.keys.front().second;
  if (f >= d.keys.back().first) return d.keys.back().second;
  for (size_t k = 0; k + 1 < d.keys.size(); ++k)
    if (f <= d.keys[k + 1].first) {
      const double s = (f - d.keys[k].first) / (d.keys[k + 1].first - d.keys[k].first);
      return (1 - s) * d.keys[k].second + s * d.keys[k + 1].second;
    }
  return d.keys.back().second;
}

std::unique_ptr<pipeline::Driver> simulation_driver(const Scene& sc, const SceneModels& m) {
  const sim::Material mat{sc.material.young, sc.material.poisson, sc.material.density};
  sim::Parameters p;
  p.dt = sc.simulation.dt;
  p.substeps = sc.simulation.substeps;
  p.gravity = sc.simulation.gravity;
  p.mass_damping = sc.simulation.damping_mass;
  p.stiffness_damping = sc.simulation.damping_stiffness;
  p.newton_iterations = sc.simulation.newton_iterations;
  if (sc.simulation.ground) {
    p.ground = true;
    p.ground_plane.normal = Eigen::Vector3d::UnitY();
    p.ground_plane.offset = *sc.simulation.ground;
  }
  sim::Simulator simulator(m.U, m.T, mat, p);
  for (const ConstraintSpec& c : sc.constraints) {
    const std::vector<int> nodes = select_nodes(c.select, m.U);
    if (c.kind == ConstraintSpec::Kind::Fixed) {
      simulator.fix(nodes);
    } else {
      sim::RigidMotion rm;
      rm.center = c.motion.twist_center;
      rm.axis = c.motion.twist_axis;
      rm.angular_velocity = c.motion.twist_rate;
      rm.velocity = c.motion.velocity;
      rm.start = c.motion.start;
      rm.stop = c.motion.stop;
      simulator.add_kinematic(nodes, rm);
    }
  }
  auto driver = std::make_unique<pipeline::SimulatorDriver>(std::move(simulator));
  for (const PokeSpec& ps : sc.pokes) {
    Eigen::MatrixXd q = ps.point.transpose();
    if (ps.relative) {  // `at`: the dense vertex nearest to a point given in bounding-box fractions
      const Eigen::RowVector3d lo = m.dense.V.colwise().minCoeff(), hi = m.dense.V.colwise().maxCoeff();
      const Eigen::RowVector3d want = lo + ps.point.transpose().cwiseProduct(hi - lo);
      Eigen::Index best = 0;
      (m.dense.V.rowwise() - want).rowwise().squaredNorm().minCoeff(&best);
      q = m.dense.V.row(best);
    }
    interp::Embedding e;
    try {
      e = interp::embed(m.U, m.T, q);
    } catch (const interp::Error& err) {
      throw SceneError(sc.file.string() + ": pokes: point (" + format_num(ps.point.x()) + ", " +
                       format_num(ps.point.y()) + ", " + format_num(ps.point.z()) + "): " + err.what());
    }
    if (!e.outside.empty())
      throw SceneError(sc.file.string() + ": pokes: point (" + format_num(ps.point.x()) + ", " +
                       format_num(ps.point.y()) + ", " + format_num(ps.point.z()) +
                       ") is outside the control mesh");
    const Eigen::Vector4d bary = e.bary.row(0).transpose();
    if (ps.force) {
      driver->add_scripted_force(ps.first, ps.last, e.element(0), bary, *ps.force);
    } else {
      const double size = ps.offset_in_sizes ? (m.dense.V.colwise().maxCoeff() - m.dense.V.colwise().minCoeff()).norm()
                                             : 1.0;
      const Eigen::Vector3d target = ps.target_relative ? Eigen::Vector3d(size * *ps.target + q.row(0).transpose())
                                                        : *ps.target;
      driver->add_scripted_spring(ps.first, ps.last, e.element(0), bary, target, ps.stiffness);
    }
  }
  return driver;
}

std::unique_ptr<pipeline::Driver> drag_driver(const Scene& sc, const SceneModels& m) {
  const int d = m.dim();
  std::vector<int> vertices;  // handles
  std::vector<int> drag_of;   // which [[drags]] entry moves each handle
  for (size_t k = 0; k < sc.drags.size(); ++k) {
    const DragSpec& dr = sc.drags[k];
    std::vector<int> vs;
    if (dr.select) {
      vs = select_nodes(*dr.select, m.U);
    } else if (dr.near) {
      Eigen::Index v = 0;
      (m.U.rowwise() - dr.near->head(d).transpose()).rowwise().squaredNorm().minCoeff(&v);
      vs.push_back(static_cast<int>(v));
    } else {
      vs.push_back(dr.vertex);
    }
    for (int v : vs) {
      if (v >= m.U.rows())
        throw SceneError(sc.file.string() + ": drags[" + std::to_string(k) + "]: vertex " + std::to_string(v) +
                         " out of range (control mesh has " + std::to_string(m.U.rows()) + ")");
      if (std::find(vertices.begin(), vertices.end(), v) != vertices.end())
        throw SceneError(sc.file.string() + ": drags[" + std::to_string(k) + "]: control vertex " +
                         std::to_string(v) + " is dragged twice");
      vertices.push_back(v);
      drag_of.push_back(static_cast<int>(k));
    }
  }
  interp::ControlOptions co;
  co.interp.alpha = sc.interpolation.alpha;
  co.interp.pin_boundary = sc.interpolation.pin_boundary;
  co.mode = sc.interpolation.handles;
  const Eigen::MatrixXd U = m.U;
  auto targets = [U, vertices, drag_of, drags = sc.drags, d](int f) {
    Eigen::MatrixXd t(static_cast<Eigen::Index>(vertices.size()), d);
    for (size_t k = 0; k < vertices.size(); ++k)
      t.row(static_cast<Eigen::Index>(k)) =
          U.row(vertices[k]) + key_at(drags[static_cast<size_t>(drag_of[k])], f).head(d).transpose();
    return t;
  };
  return std::make_unique<pipeline::HandleDriver>(m.U, m.T, vertices, co, targets);
}

// Area-weighted vertex normals of a triangle surface (rest normals for the GPU's shading).
Eigen::MatrixXd vertex_normals(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(V.rows(), 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const Eigen::RowVector3d n = (b - a).cross(c - a).transpose();
    for (int k = 0; k < 3; ++k) N.row(F(f, k)) += n;
  }
  for (Eigen::Index i = 0; i < N.rows(); ++i) {
    const double len = N.row(i).norm();
    if (len > 0) N.row(i) /= len;
    else N.row(i) << 0, 0, 1;  // a vertex no face uses
  }
  return N;
}

}  // namespace

std::unique_ptr<pipeline::Driver> make_driver(const Scene& sc, const SceneModels& m) {
  if (sc.mode == Mode::Simulate && m.dim() != 3)
    throw SceneError(sc.file.string() + ": mode = \"simulate\" needs a 3D control mesh (use mode = \"drag\" in 2D)");
  return sc.mode == Mode::Simulate ? simulation_driver(sc, m) : drag_driver(sc, m);
}

pipeline::FramePipeline make_pipeline(const Scene& sc, const SceneModels& m,
                                      interp::Embedding embedding,
                                      std::unique_ptr<pipeline::Evaluator> evaluator) {
  if (sc.mode == Mode::Simulate && m.dim() != 3)
    throw SceneError(sc.file.string() + ": mode = \"simulate\" needs a 3D control mesh (use mode = \"drag\" in 2D)");
  pipeline::PipelineOptions po;
  po.method = sc.interpolation.method;
  po.interp.alpha = sc.interpolation.alpha;
  po.interp.pin_boundary = sc.interpolation.pin_boundary;
  auto driver = sc.mode == Mode::Simulate ? simulation_driver(sc, m) : drag_driver(sc, m);
  // rest normals of a 3D surface: evaluated normals for the GPU's pictures and the viewer; a
  // model with normals of its own has them evaluated every frame (written with the meshes)
  const bool file_normals = m.dim() == 3 && m.dense.N.rows() == m.dense.V.rows() && m.dense.N.cols() == 3;
  po.normals = file_normals;
  const Eigen::MatrixXd normals = file_normals ? m.dense.N
                                  : m.dim() == 3 && m.dense.F.rows() > 0 ? vertex_normals(m.dense.V, m.dense.F)
                                                                         : Eigen::MatrixXd();
  return pipeline::FramePipeline(m.U, m.T, std::move(embedding), std::move(driver), po,
                                 std::move(evaluator), normals);
}

namespace {

// The 3D pictures of a run: the Bezier points of each written frame's panels are kept (a few
// hundred kB), and the pictures are drawn at the end, all the same size, with one camera that
// frames the control mesh over the whole run (GPU renderer from the evaluator's buffers, or the
// CPU rasteriser).
class Pictures3D {
 public:
  Pictures3D(const Scene& sc, const SceneModels& m, const fs::path& dir) : sc_(sc), m_(m), dir_(dir) {
    lo_.setZero();
    hi_.setZero();
    if (m.dim() != 3) return;  // 2D pictures are written as the frames come
    lo_ = m.U.colwise().minCoeff().transpose();
    hi_ = m.U.colwise().maxCoeff().transpose();
  }
  void add(int f, const Eigen::MatrixXd& X, std::vector<interp::BezierPoints> panels) {
    if (X.cols() != 3) throw SceneError("3D pictures need 3D control positions");
    lo_ = lo_.cwiseMin(X.colwise().minCoeff().transpose());
    hi_ = hi_.cwiseMax(X.colwise().maxCoeff().transpose());
    frames_.push_back({f, std::move(panels)});
  }
  /// Draws and writes every stored picture; gpu/renderer null: the CPU rasteriser.
  void write(pipeline::FramePipeline& pipe, gpu::GpuEvaluator* gpu, gpu::Renderer* renderer) {
    if (frames_.empty()) return;
    const Eigen::Vector3d up = sc_.output.up.normalized();
    Eigen::Vector3d side = up.cross(Eigen::Vector3d::UnitX());
    if (side.norm() < 0.5) side = up.cross(Eigen::Vector3d::UnitY());
    side.normalize();
    const Eigen::Vector3d front = side.cross(up);
    Eigen::MatrixXd corners(2, 3);
    corners.row(0) = lo_.transpose();
    corners.row(1) = hi_.transpose();
    raster::View view = raster::frame_points(corners, -(0.75 * front + 0.6 * side + 0.45 * up), up);
    view.bounds_min = lo_;
    view.bounds_max = hi_;
    const int h = 480;
    const int w = std::clamp(static_cast<int>(h * raster::view_aspect(view)), 160, 960);
    Eigen::MatrixXd V;
    for (const Frame& fr : frames_) {
      std::vector<Image> panels;
      for (const interp::BezierPoints& B : fr.panels) {
        if (gpu && renderer) {
          gpu->evaluate(B, true);
          panels.push_back(renderer->render(*gpu, view, w, h));
        } else {
          interp::evaluate<double>(B, pipe.embedding(), V);
          panels.push_back(raster::render_mesh(V, m_.dense.F, view, w, h));
        }
      }
      io::write_png(io::frame_path(dir_ / "frame", fr.f, ".png"), raster::side_by_side(panels));
    }
  }

 private:
  struct Frame {
    int f;
    std::vector<interp::BezierPoints> panels;
  };
  const Scene& sc_;
  const SceneModels& m_;
  fs::path dir_;
  Eigen::Vector3d lo_, hi_;
  std::vector<Frame> frames_;
};

class Outputs {
 public:
  Outputs(const Scene& sc, const SceneModels& m, const fs::path& dir) : sc_(sc), m_(m), dir_(dir) {
    if (sc.output.pc2) pc2_ = std::make_unique<io::Pc2Writer>(dir / "dense.pc2", static_cast<int>(m.dense.V.rows()), 0.0f, 1.0f);
  }
  bool due(int frame, int last) const { return frame % sc_.output.every == 0 || frame == last; }

  /// Every frame: the point cache of `dense` (the run's method). Written frames: mesh, control
  /// VTK, and in 2D the picture (`shown`: BI | the run's method | boundary-pinned).
  void frame(int f, const Eigen::MatrixXd& Xc, const Eigen::MatrixXd& dense,
             const std::vector<const Eigen::MatrixXd*>& shown, bool write_now,
             const Eigen::MatrixXd* normals) {
    if (pc2_) {
      if (dense.cols() == 2 && m_.flat_z) {  // a flat model keeps its plane's z, as in its meshes
        flat_.resize(dense.rows(), 3);
        flat_.leftCols(2) = dense;
        flat_.col(2).setConstant(*m_.flat_z);
        pc2_->append(flat_);
      } else {
        pc2_->append(dense);
      }
    }
    if (!write_now) return;
    if (sc_.output.mesh_format != MeshFormat::None) {
      const std::string ext = std::string(".") + format_name(sc_.output.mesh_format);
      const io::Encoding enc = sc_.output.mesh_format == MeshFormat::Ply ? io::Encoding::binary : io::Encoding::ascii;
      if (dense.cols() == 3) {
        io::write_frame(dir_ / "mesh", f, ext, m_.dense, dense, enc,
                        normals ? *normals : Eigen::MatrixXd());
      } else {  // 2D: z = 0, or the plane of a flat model
        Eigen::MatrixXd V3 = Eigen::MatrixXd::Constant(dense.rows(), 3, m_.flat_z.value_or(0.0));
        V3.leftCols(dense.cols()) = dense;
        io::write_frame(dir_ / "mesh", f, ext, m_.dense, V3, enc);
      }
    }
    if (sc_.output.control_vtk) {
      const Eigen::MatrixXd disp = Xc - m_.U;
      io::write_vtk(io::frame_path(dir_ / "control", f, ".vtk"), Xc, m_.T, disp);
    }
    if (sc_.output.image && !shown.empty() && m_.image) {
      std::vector<Image> panels;
      const int W = m_.image->width, H = m_.image->height;
      const int ow = W * 3 / 2, oh = H * 3 / 2;
      const Eigen::RowVector2d off(W / 4.0, H / 4.0);
      for (const Eigen::MatrixXd* p : shown) {
        const Eigen::MatrixXd Dp = p->rowwise() + off;
        panels.push_back(raster::warp_image(*m_.image, m_.dense.V, Dp, m_.dense.F, ow, oh));
      }
      io::write_png(io::frame_path(dir_ / "frame", f, ".png"), raster::side_by_side(panels));
    }
  }
  void finish() {
    if (pc2_) pc2_->finish();
  }

 private:
  const Scene& sc_;
  const SceneModels& m_;
  fs::path dir_;
  std::unique_ptr<io::Pc2Writer> pc2_;
  Eigen::MatrixXd flat_;  // a flat 2D model's positions with its z, for the point cache
};

}  // namespace

namespace {
// The names of the files run_scene writes into its output folder.
const std::regex& output_names() {
  static const std::regex ours(R"((mesh_[0-9]+\.(obj|ply)|control_[0-9]+\.vtk|frame_[0-9]+\.png|dense\.pc2|metrics\.json))");
  return ours;
}

// Removes the files of an earlier run (only names that run_scene writes) from `dir`, so that
// --force does not leave its extra frames beside the new ones.
// Also the temporaries a killed run left there (".mbi-tmp.<pid>.*" of a process that is gone).
// A symbolic link under one of these names is removed itself, never followed.
void clear_outputs(const fs::path& dir) {
  std::vector<fs::path> old;
  for (const auto& e : fs::directory_iterator(dir))
    if ((e.is_symlink() || e.is_regular_file()) && std::regex_match(e.path().filename().string(), output_names()))
      old.push_back(e.path());
  for (const auto& p : old) fs::remove(p);
  io::remove_stale_temporaries(dir);
}
}  // namespace

namespace {

// The scene's inputs that are files (what --force must never remove or replace).
std::vector<fs::path> input_files(const Scene& sc, const RunOptions& opt) {
  std::vector<fs::path> in{sc.file};
  if (!opt.mesh.empty()) in.push_back(opt.mesh);
  if (!sc.dense.path.empty()) in.push_back(resolve(sc, sc.dense.path));
  if (!sc.dense.image.empty()) in.push_back(resolve(sc, sc.dense.image));
  if (!sc.control.path.empty()) {
    fs::path c = resolve(sc, sc.control.path);
    in.push_back(c);
    fs::path base = c;
    base.replace_extension();
    for (const char* e : {".node", ".ele"}) {
      fs::path p = base;
      p += e;
      in.push_back(p);
    }
  }
  return in;
}

// An input in the output folder under one of the run's output names would be replaced (or, with
// --force, removed): refused, whatever its spelling (file identity).
void check_inputs_outside(const Scene& sc, const RunOptions& opt, const fs::path& dir) {
  const auto dir_id = io::file_id(dir);
  if (!dir_id) return;
  for (const fs::path& in : input_files(sc, opt)) {
    const auto id = io::file_id(in);
    if (!id) continue;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      if (!std::regex_match(e.path().filename().string(), output_names())) continue;
      if (io::file_id(e.path()) == id)
        throw SceneError(in.string() + ": is an input and also " + e.path().string() +
                         ", a file this run writes; an input is never overwritten, not even with --force");
    }
  }
}

// Pictures that could not be written fail at load, not after frame 0: 2D panels are the image's
// size x 1.5 each, side by side with 8-pixel gaps; io::Image holds at most 16384 x 16384.
void check_picture_size(const Scene& sc, const SceneModels& m) {
  if (!sc.output.image || !m.image || m.dim() != 2) return;
  const long long panels = (sc.interpolation.method == pipeline::Method::Phong ? 3 : 2) +
                           (sc.mode == Mode::Drag && sc.interpolation.compare_pinned &&
                                    !sc.interpolation.pin_boundary
                                ? 1
                                : 0);
  const long long ow = static_cast<long long>(m.image->width) * 3 / 2;
  const long long oh = static_cast<long long>(m.image->height) * 3 / 2;
  const long long w = panels * ow + 8 * (panels - 1);
  if (w > io::kMaxImageSide || oh > io::kMaxImageSide)
    throw SceneError(m.dense_name + ": a " + std::to_string(m.image->width) + " x " +
                     std::to_string(m.image->height) + " image makes " + std::to_string(w) + " x " +
                     std::to_string(oh) + " pictures (" + std::to_string(panels) +
                     " panels at 1.5 times its size), more than " + std::to_string(io::kMaxImageSide) +
                     " pixels a side; use a smaller "
                     "image or output.image = false");
}

}  // namespace

fs::path output_folder(const Scene& sc, const fs::path& out_dir) {
  if (!out_dir.empty()) return out_dir;
  // The scene's name, verbatim, as one path component under out/: a downloaded scene never
  // writes outside it.
  const std::string& n = sc.name;
  const bool bad = n.empty() || n == "." || n == ".." || n.front() == '.' ||
                   n.find_first_of("/\\") != std::string::npos ||
                   std::any_of(n.begin(), n.end(), [](char c) {
                     return static_cast<unsigned char>(c) < 0x20 || c == 0x7f;
                   }) ||
                   n.size() > 200;
  if (bad) {
    std::string shown;
    for (char c : n) shown += static_cast<unsigned char>(c) < 0x20 || c == 0x7f ? '?' : c;
    throw SceneError(sc.file.string() + ": name = \"" + shown +
                     "\" cannot name an output folder: it must be one file name (no '/', '\\', "
                     "control characters, leading '.', at most 200 bytes); give --out DIR to "
                     "choose the folder");
  }
  return fs::path("out") / n;
}

RunResult run_scene(const Scene& sc_in, const RunOptions& opt) {
  Scene sc = sc_in;
  if (opt.method) sc.interpolation.method = *opt.method;
  if (opt.frames > 0) sc.simulation.frames = opt.frames;
  if (opt.gpu) sc.interpolation.gpu = *opt.gpu;
  const int frames = sc.simulation.frames;
  auto log = [&](const std::string& s) {
    if (opt.log) opt.log(s);
  };
  auto warn = [&](const std::string& s) {
    if (opt.warn) opt.warn(s);
    else log(s);
  };

  RunResult res;
  res.out_dir = output_folder(sc, opt.out_dir);
  {
    std::error_code ec;
    const auto st = fs::symlink_status(res.out_dir, ec);
    if (opt.out_dir.empty() && fs::is_symlink(st))
      throw SceneError(res.out_dir.string() +
                       ": is a symbolic link; a scene's default output folder is never reached "
                       "through one (give --out to choose a folder)");
    if (fs::exists(st) || fs::is_symlink(st)) {
      if (!fs::is_directory(res.out_dir, ec))
        throw SceneError(res.out_dir.string() + ": exists and is not a folder");
      if (!fs::is_empty(res.out_dir, ec) && !opt.force)
        throw SceneError(res.out_dir.string() + ": exists and is not empty (use --force to overwrite)");
      check_inputs_outside(sc, opt, res.out_dir);
    } else {
      // the folder will be made: its parent must be a folder (or be makeable)
      for (fs::path p = res.out_dir.parent_path(); !p.empty(); p = p.parent_path()) {
        const auto ps = fs::status(p, ec);
        if (fs::exists(ps)) {
          if (!fs::is_directory(ps))
            throw SceneError(res.out_dir.string() + ": cannot make this folder: " + p.string() +
                             " is not a folder");
          break;
        }
        if (p == p.parent_path()) break;
      }
    }
  }

  // ---------------------------------------------------------------- models, embedding, pipeline
  nlohmann::json metrics;
  auto t0 = Clock::now();
  const SceneModels m = load_models(sc, opt.mesh, opt.force_3d);
  const double load_ms = ms_since(t0);
  check_picture_size(sc, m);
  const int d = m.dim();

  t0 = Clock::now();
  interp::Embedding emb = interp::embed(m.U, m.T, m.dense.V);
  const double embed_ms = ms_since(t0);
  res.outside_points = static_cast<int>(emb.outside.size());
  if (!emb.outside.empty())
    warn("warning: " + std::to_string(emb.outside.size()) + " dense vertices lie outside the control mesh (farthest " +
        format_num(emb.max_outside_distance) + "); they follow the nearest element by extrapolation");
  const size_t outside = emb.outside.size();

  // 2D drag scenes may compare with the boundary-pinned variant (paper Figure 8c): a second
  // pipeline with the same drags.
  std::optional<pipeline::FramePipeline> pinned;
  if (sc.mode == Mode::Drag && sc.interpolation.compare_pinned && !sc.interpolation.pin_boundary) {
    Scene sp = sc;
    sp.interpolation.pin_boundary = true;
    pinned.emplace(make_pipeline(sp, m, emb));
  }
  // the evaluator: GPU (transform feedback) when asked for and possible, else CPU (double)
  std::unique_ptr<gpu::Context> gl;
  if (sc.interpolation.gpu != GpuUse::Off) {
    try {
      gl = gpu::Context::headless();
    } catch (const gpu::GlError& e) {
      if (sc.interpolation.gpu == GpuUse::On)
        throw SceneError(std::string("gpu = on, but ") + e.what());
      warn(std::string("note: ") + e.what() + "; evaluating and drawing on the CPU");
    }
  }
  gpu::GpuEvaluator* gpu_eval = nullptr;
  std::unique_ptr<pipeline::Evaluator> evaluator;
  if (gl) {
    auto g = std::make_unique<gpu::GpuEvaluator>(*gl);
    gpu_eval = g.get();
    evaluator = std::move(g);
  }
  pipeline::FramePipeline pipe = make_pipeline(sc, m, std::move(emb), std::move(evaluator));
  res.evaluator = pipe.evaluator().name();
  std::unique_ptr<gpu::Renderer> renderer;
  if (gl && d == 3 && sc.output.image) {
    renderer = std::make_unique<gpu::Renderer>(*gl);
    renderer->set_faces(m.dense.F);
  }
  const interp::ModifiedBI& solver = pipe.solver();  // metrics: alpha, beta, the energies

  log("dense: " + m.dense_name + " (" + std::to_string(m.dense.V.rows()) + " vertices)");
  log("control: " + m.control_name + ": " + std::to_string(m.U.rows()) + " vertices, " +
      std::to_string(m.T.rows()) + (d == 3 ? " tetrahedra" : " triangles"));

  metrics["scene"] = sc.name;
  metrics["scene_file"] = sc.file.string();
  metrics["mode"] = mode_name(sc.mode);
  metrics["dim"] = d;
  metrics["method"] = pipeline::method_name(sc.interpolation.method);
  metrics["alpha"] = solver.alpha();
  metrics["beta"] = solver.beta();
  metrics["pin_boundary"] = sc.interpolation.pin_boundary;
  metrics["dense_vertices"] = m.dense.V.rows();
  metrics["control_vertices"] = m.U.rows();
  metrics["elements"] = m.T.rows();
  metrics["outside_points"] = outside;
  metrics["evaluator"] = res.evaluator;
  metrics["renderer"] = d == 3 && sc.output.image ? (renderer ? "gpu" : "cpu") : "cpu";
  metrics["timings_ms"] = {{"load", load_ms}, {"generate", m.generate_seconds * 1e3},
                           {"embed", embed_ms}, {"precompute", pipe.precompute_ms()}};
  if (pipe.method() == pipeline::Method::Phong)
    metrics["timings_ms"]["phong_precompute"] = pipe.phong_precompute_ms();
  metrics["frames"] = nlohmann::json::array();

  // ---------------------------------------------------------------- frames
  if (opt.force && fs::exists(res.out_dir)) clear_outputs(res.out_dir);
  fs::create_directories(res.out_dir);
  Outputs out(sc, m, res.out_dir);
  Pictures3D pictures(sc, m, res.out_dir);
  auto* sim_driver = dynamic_cast<pipeline::SimulatorDriver*>(&pipe.driver());
  std::vector<Eigen::MatrixXd> others;  // the picture's other methods
  const bool with_phong = pipe.method() == pipeline::Method::Phong;
  auto table_now = [&] {
    return with_phong ? interp::discontinuity_table(solver, pipe.control_positions(), pipe.modified_bi_M(), pipe.phong_M())
                      : interp::discontinuity_table(solver, pipe.control_positions(), pipe.modified_bi_M());
  };
  const double roundoff = disc_roundoff(m.U);
  // A failing step, or an error while writing a frame (a result that does not fit a file, a full
  // disk), ends the run (exit 3): every output written so far is kept, and metrics.json tells
  // how far the run got.
  auto fail_run = [&](const std::string& what) {
    if (!res.failed) {
      res.failed = true;
      res.message = what;
    }
  };
  for (int f = 0; f <= frames && !res.failed; ++f) {
    try {
      nlohmann::json fr;
      fr["frame"] = f;
      const pipeline::FrameResult r = pipe.step();
      if (!r.ok) {
        fail_run(r.message);
        break;
      }
      if (sim_driver) {
        fr["time"] = sim_driver->simulator().time();
        fr["newton_iterations"] = f > 0 ? sim_driver->last_step().newton_iterations : 0;
        fr["solver_iterations"] = f > 0 ? sim_driver->last_step().solver_iterations : 0;
      }
      if (pinned && !pinned->step(false).ok) throw SceneError("the boundary-pinned comparison failed");
      const pipeline::FrameTimings& tm = pipe.timings();
      const bool write_now = out.due(f, frames);
      std::vector<const Eigen::MatrixXd*> shown;
      std::optional<std::vector<interp::BezierPoints>> picture;
      if (write_now && sc.output.image) {
        // BI | modified-BI (BI | Phong | modified-BI for a Phong run)
        std::vector<pipeline::Method> panels{pipeline::Method::BI, pipeline::Method::ModifiedBI};
        if (pipe.method() == pipeline::Method::Phong) panels.insert(panels.begin() + 1, pipeline::Method::Phong);
        if (d == 3) {  // drawn after the run, from the Bezier points
          picture.emplace();
          for (pipeline::Method k : panels) picture->push_back(pipe.bezier_with(k));
        } else {  // the run's method is evaluated already, the others only here (| pinned)
          others.resize(panels.size());
          for (size_t k = 0; k < panels.size(); ++k) {
            if (panels[k] == pipe.method()) {
              shown.push_back(&pipe.positions());
            } else {
              pipe.evaluate_with(panels[k], others[k]);
              shown.push_back(&others[k]);
            }
          }
          if (pinned) shown.push_back(&pinned->positions());
        }
      }
      // metrics: BI against modified-BI (and Phong) at the same control positions
      const bool last = f == frames;
      fr["sim_ms"] = sim_driver && f > 0 ? sim_driver->last_step().total_ms : 0.0;
      fr["drive_ms"] = tm.drive_ms;
      fr["solve_ms"] = tm.solve_ms + (sim_driver ? 0.0 : tm.drive_ms);  // handles: the joint solve
      fr["bezier_ms"] = tm.bezier_ms;
      fr["interp_ms"] = tm.bezier_ms + tm.evaluate_ms;
      fr["upload_ms"] = pipe.evaluator().timings().upload_ms;
      fr["pass_ms"] = pipe.evaluator().timings().pass_ms;
      // numbers stay numbers: positions or energies that overflow fail this step (exit 3, what
      // was reached is kept), before anything of this frame is written
      if (!pipe.positions().allFinite() || !pipe.control_positions().allFinite())
        throw SceneError("the positions overflow (not finite)");
      std::optional<interp::DiscontinuityTable> table;
      if (sc.output.metrics || last) {
        t0 = Clock::now();
        try {
          table = table_now();
        } catch (const interp::OverflowError& e) {  // without the library function's name
          const std::string w = e.what(), who = "discontinuity_table: ";
          throw SceneError(w.rfind(who, 0) == 0 ? w.substr(who.size()) : w);
        }
        fr["disc"] = disc_json(*table, roundoff);  // throws on a non-finite value
        if (!std::isfinite(table->e_vibr) || !std::isfinite(table->e_disc))
          throw SceneError("E_vibr or E_disc is not finite");
        fr["e_vibr"] = table->e_vibr;
        fr["e_disc"] = table->e_disc;
        fr["metrics_ms"] = ms_since(t0);
      }
      out.frame(f, pipe.control_positions(), pipe.positions(), shown, write_now,
                write_now && pipe.options().normals ? &pipe.normals() : nullptr);
      if (picture) pictures.add(f, pipe.control_positions(), std::move(*picture));
      if (table) res.last_table = *table;
      metrics["frames"].push_back(fr);
      res.frames = f;
      if (opt.progress) opt.progress(f, frames);
    } catch (const std::exception& e) {
      fail_run("frame " + std::to_string(f) + ": " + e.what());
    }
  }
  try {
    out.finish();
  } catch (const std::exception& e) {
    fail_run(std::string("dense.pc2: ") + e.what());
  }
  t0 = Clock::now();
  try {
    pictures.write(pipe, gpu_eval, renderer.get());  // also after a failed step: what was reached
  } catch (const std::exception& e) {
    fail_run(std::string("pictures: ") + e.what());
  }
  metrics["timings_ms"]["pictures"] = ms_since(t0);
  metrics["frames_completed"] = res.frames;
  metrics["failure"] = res.failed ? nlohmann::json(res.message) : nlohmann::json(nullptr);
  // the table of the last good frame: computed above when metrics are written or the run reached
  // its last frame; otherwise (a failed run without metrics) here, for the summary printed
  if (res.failed && !sc.output.metrics && pipe.frame() >= 0) {
    try {
      res.last_table = table_now();
    } catch (const std::exception&) {  // the failure is reported already
    }
  }
  const nlohmann::json& frames_json = metrics["frames"];
  const bool has_disc = !frames_json.empty() && frames_json.back().contains("disc");
  metrics["last_disc"] = has_disc ? frames_json.back()["disc"]
                         : frames_json.empty() ? nlohmann::json(nullptr)
                                               : disc_json(res.last_table, roundoff);
  if (sc.output.metrics) {
    try {
      io::write_text_atomic(res.out_dir / "metrics.json", metrics.dump(1) + "\n");
    } catch (const std::exception& e) {
      fail_run(std::string("metrics.json: ") + e.what());
    }
  }
  res.roundoff = roundoff;
  return res;
}

}  // namespace mbi::scenes
