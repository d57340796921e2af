#include <mbi/interp.hpp>
#include <mbi/scenes/cage.hpp>
#include <mbi/scenes/json_util.hpp>
#include <mbi/scenes/procedural.hpp>
#include <mbi/scenes/runner.hpp>
#include <mbi/sim/simulator.hpp>

#include <Eigen/Geometry>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

namespace fs = std::filesystem;

namespace mbi::scenes {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

fs::path resolve(const Scene& sc, const fs::path& p) {
  if (p.is_absolute()) return p;
  return sc.file.parent_path() / p;
}

// Loop subdivision with OpenMesh (smooth densification of a triangle surface).
void loop_subdivide(SurfaceMesh& m, int steps) {
  using Mesh = OpenMesh::TriMesh_ArrayKernelT<>;
  Mesh mesh;
  std::vector<Mesh::VertexHandle> vh;
  vh.reserve(static_cast<size_t>(m.V.rows()));
  for (Eigen::Index i = 0; i < m.V.rows(); ++i)
    vh.push_back(mesh.add_vertex(Mesh::Point(static_cast<float>(m.V(i, 0)),
                                             static_cast<float>(m.V(i, 1)),
                                             static_cast<float>(m.V(i, 2)))));
  int skipped = 0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const auto fh = mesh.add_face(vh[static_cast<size_t>(m.F(f, 0))], vh[static_cast<size_t>(m.F(f, 1))],
                                  vh[static_cast<size_t>(m.F(f, 2))]);
    if (!fh.is_valid()) ++skipped;
  }
  if (skipped)
    throw SceneError("dense.subdivide: the mesh has " + std::to_string(skipped) +
                     " non-manifold faces; Loop subdivision needs a manifold surface");
  OpenMesh::Subdivider::Uniform::LoopT<Mesh> loop;
  loop.attach(mesh);
  loop(static_cast<size_t>(steps));
  loop.detach();
  mesh.garbage_collection();
  m.V.resize(static_cast<Eigen::Index>(mesh.n_vertices()), 3);
  for (const auto v : mesh.vertices()) {
    const auto p = mesh.point(v);
    m.V.row(v.idx()) << p[0], p[1], p[2];
  }
  m.F.resize(static_cast<Eigen::Index>(mesh.n_faces()), 3);
  for (const auto f : mesh.faces()) {
    int k = 0;
    for (const auto v : mesh.fv_range(f)) m.F(f.idx(), k++) = v.idx();
  }
  m.polygons.clear();
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

SceneModels load_models(const Scene& sc, const fs::path& mesh_override) {
  SceneModels m;
  const std::string where = sc.file.string();
  // ------------------------------------------------------------------ dense
  if (!mesh_override.empty()) {
    m.dense = read_surface(mesh_override);
    m.dense_name = mesh_override.string();
  } else if (!sc.dense.path.empty()) {
    const fs::path p = resolve(sc, sc.dense.path);
    m.dense = read_surface(p);
    m.dense_name = p.string();
  } else if (sc.dense.builtin == "paper-bar") {
    paper_bar_surface(m.dense.V, m.dense.F);
    m.dense_name = "built-in paper bar";
  } else if (sc.dense.builtin == "cylinder") {
    cylinder_surface(0.5, 4.0, 96, 192, 12, m.dense.V, m.dense.F);
    m.dense_name = "built-in cylinder";
  } else if (sc.dense.builtin == "bumpy-sphere") {
    bumpy_sphere(1.0, 205, 0.05, m.dense.V, m.dense.F);
    m.dense_name = "built-in bumpy sphere";
  } else if (sc.dense.builtin == "image-grid") {
    Image img = sc.dense.image.empty() ? test_pattern(512, 384) : read_png(resolve(sc, sc.dense.image));
    const int longer = std::max(img.width, img.height);
    const int gx = std::max(2, sc.dense.grid * img.width / longer);
    const int gy = std::max(2, sc.dense.grid * img.height / longer);
    grid_2d(img.width, img.height, gx, gy, m.dense.V, m.dense.F);
    m.dense_name = sc.dense.image.empty() ? "built-in test pattern" : resolve(sc, sc.dense.image).string();
    m.image = std::move(img);
  }
  if (sc.dense.subdivide > 0) {
    if (m.dense.V.cols() != 3) throw SceneError(where + ": dense.subdivide: only for 3D surfaces");
    loop_subdivide(m.dense, sc.dense.subdivide);
  }
  if (m.dense.V.rows() == 0) throw SceneError(m.dense_name + ": the dense model has no vertices");

  // ------------------------------------------------------------------ control
  const bool two_d = m.dense.V.cols() == 2;
  if (!sc.control.path.empty()) {
    const fs::path p = resolve(sc, sc.control.path);
    const ControlMesh cm = read_control_mesh(p);
    m.U = cm.U;
    m.T = cm.T;
    m.control_name = p.string();
  } else if (sc.control.builtin == "paper-bar") {
    paper_bar_control(m.U, m.T);
    m.control_name = "built-in paper bar control (35 vertices)";
  } else if (sc.control.builtin == "box") {
    if (two_d) throw SceneError(where + ": control.builtin = \"box\" is 3D; use \"grid-2d\"");
    m.U = padded_box_control(m.dense.V, sc.control.cells, m.T);
    m.control_name = "built-in box control";
  } else if (sc.control.builtin == "grid-2d") {
    if (!two_d) throw SceneError(where + ": control.builtin = \"grid-2d\" needs a 2D dense model");
    const Eigen::Vector2d lo = m.dense.V.colwise().minCoeff().transpose();
    const Eigen::Vector2d hi = m.dense.V.colwise().maxCoeff().transpose();
    Eigen::MatrixXd G;
    grid_2d(hi.x() - lo.x(), hi.y() - lo.y(), sc.control.cells.x(), sc.control.cells.y(), G, m.T);
    m.U = G.rowwise() + lo.transpose();
    m.control_name = "built-in 2D grid control";
  } else {
    CageOptions co;
    co.target_vertices = sc.control.generate_vertices;
    co.mesher = parse_mesher(sc.control.mesher);
    const CageResult cage = make_cage(m.dense.V, m.dense.F, co);
    m.U = cage.U;
    m.T = cage.T;
    m.generate_seconds = cage.seconds;
    m.control_name = std::string("generated control mesh (") + mesher_name(cage.mesher) + ", " +
                     std::to_string(cage.U.rows()) + " vertices, min dihedral " +
                     format_num(cage.min_dihedral_deg) + " deg)";
  }
  if (m.U.cols() != m.dense.V.cols())
    throw SceneError(where + ": the control mesh is " + std::to_string(m.U.cols()) +
                     "D but the dense model is " + std::to_string(m.dense.V.cols()) + "D");
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

class Outputs {
 public:
  Outputs(const Scene& sc, const SceneModels& m, const fs::path& dir) : sc_(sc), m_(m), dir_(dir) {
    if (sc.output.pc2) pc2_ = std::make_unique<Pc2Writer>(dir / "dense.pc2", static_cast<int>(m.dense.V.rows()), 0.0f, 1.0f);
    if (m.dim() == 3) {
      // look from the front-right and slightly above, relative to the scene's up axis
      const Eigen::Vector3d up = sc.output.up.normalized();
      Eigen::Vector3d side = up.cross(Eigen::Vector3d::UnitX());
      if (side.norm() < 0.5) side = up.cross(Eigen::Vector3d::UnitY());
      side.normalize();
      const Eigen::Vector3d front = side.cross(up);
      view_ = frame_points(m.U, -(0.75 * front + 0.6 * side + 0.45 * up), up);
    }
  }
  bool due(int frame, int last) const { return frame % sc_.output.every == 0 || frame == last; }

  void frame(int f, const Eigen::MatrixXd& Xc, const Eigen::MatrixXd& dense,
             const Eigen::MatrixXd* dense_bi, const Eigen::MatrixXd* dense_pinned, bool write_now) {
    if (pc2_) pc2_->append(dense);
    if (!write_now) return;
    if (sc_.output.mesh_format != "none") {
      Eigen::MatrixXd V3 = dense;
      if (V3.cols() == 2) {
        V3.conservativeResize(Eigen::NoChange, 3);
        V3.col(2).setZero();
      }
      SurfaceMesh topo = m_.dense;
      topo.V = V3;
      write_frame(dir_ / "mesh", f, "." + sc_.output.mesh_format, topo, V3,
                  sc_.output.mesh_format == "ply" ? Encoding::binary : Encoding::ascii);
    }
    if (sc_.output.control_vtk) {
      const Eigen::MatrixXd disp = Xc - m_.U;
      write_vtk(frame_path(dir_ / "control", f, ".vtk"), Xc, m_.T, disp);
    }
    if (sc_.output.image) {
      std::vector<Image> panels;
      if (m_.dim() == 3) {
        View v = view_;
        // frame the deformed shapes (both panels share the view)
        const Eigen::MatrixXd* both[2] = {dense_bi ? dense_bi : &dense, &dense};
        v.bounds_min = both[0]->colwise().minCoeff().transpose().cwiseMin(both[1]->colwise().minCoeff().transpose());
        v.bounds_max = both[0]->colwise().maxCoeff().transpose().cwiseMax(both[1]->colwise().maxCoeff().transpose());
        const int h = 480;
        const int w = std::clamp(static_cast<int>(h * view_aspect(v)), 160, 960);
        if (dense_bi) panels.push_back(render_mesh(*dense_bi, m_.dense.F, v, w, h));
        panels.push_back(render_mesh(dense, m_.dense.F, v, w, h));
      } else if (m_.image) {
        const int W = m_.image->width, H = m_.image->height;
        const int ow = W * 3 / 2, oh = H * 3 / 2;
        const Eigen::RowVector2d off(W / 4.0, H / 4.0);
        auto warp = [&](const Eigen::MatrixXd& D) {
          const Eigen::MatrixXd Dp = D.rowwise() + off;
          return warp_image(*m_.image, m_.dense.V, Dp, m_.dense.F, ow, oh);
        };
        if (dense_bi) panels.push_back(warp(*dense_bi));
        panels.push_back(warp(dense));
        if (dense_pinned) panels.push_back(warp(*dense_pinned));
      }
      if (!panels.empty()) write_png(frame_path(dir_ / "frame", f, ".png"), side_by_side(panels));
    }
  }
  void finish() {
    if (pc2_) pc2_->finish();
  }

 private:
  const Scene& sc_;
  const SceneModels& m_;
  fs::path dir_;
  std::unique_ptr<Pc2Writer> pc2_;
  View view_;
};

}  // namespace

RunResult run_scene(const Scene& sc_in, const RunOptions& opt) {
  Scene sc = sc_in;
  if (!opt.method.empty()) sc.interpolation.method = opt.method;
  if (opt.frames > 0) sc.simulation.frames = opt.frames;
  const int frames = sc.simulation.frames;
  auto log = [&](const std::string& s) {
    if (opt.log) opt.log(s);
  };

  RunResult res;
  res.out_dir = opt.out_dir.empty() ? fs::path("out") / sc.name : opt.out_dir;
  if (fs::exists(res.out_dir)) {
    if (!fs::is_directory(res.out_dir))
      throw SceneError(res.out_dir.string() + ": exists and is not a folder");
    if (!fs::is_empty(res.out_dir) && !opt.force)
      throw SceneError(res.out_dir.string() + ": exists and is not empty (use --force to overwrite)");
  }

  // ---------------------------------------------------------------- models, embedding, precompute
  nlohmann::json metrics;
  auto t0 = Clock::now();
  const SceneModels m = load_models(sc, opt.mesh);
  const double load_ms = ms_since(t0);
  const int d = m.dim();
  if (sc.mode == "simulate" && d != 3)
    throw SceneError(sc.file.string() + ": mode = \"simulate\" needs a 3D control mesh (use mode = \"drag\" in 2D)");

  t0 = Clock::now();
  const interp::Embedding emb = interp::embed(m.U, m.T, m.dense.V);
  const double embed_ms = ms_since(t0);
  res.outside_points = static_cast<int>(emb.outside.size());
  if (!emb.outside.empty())
    log("warning: " + std::to_string(emb.outside.size()) + " dense vertices lie outside the control mesh (farthest " +
        format_num(emb.max_outside_distance) + "); they follow the nearest element by extrapolation");

  interp::Options iopt;
  iopt.alpha = sc.interpolation.alpha;
  iopt.pin_boundary = sc.interpolation.pin_boundary;
  t0 = Clock::now();
  const interp::ModifiedBI solver(m.U, m.T, iopt);
  const double precompute_ms = ms_since(t0);
  const bool use_bi = sc.interpolation.method == "bi";

  log("dense: " + m.dense_name + " (" + std::to_string(m.dense.V.rows()) + " vertices)");
  log("control: " + m.control_name + ": " + std::to_string(m.U.rows()) + " vertices, " +
      std::to_string(m.T.rows()) + (d == 3 ? " tetrahedra" : " triangles"));

  // ---------------------------------------------------------------- driver
  std::unique_ptr<sim::Simulator> simulator;
  std::unique_ptr<interp::HandleSolver> handles, handles_pinned;
  std::vector<int> drag_vertices;
  std::vector<int> drag_of;  // which [[drags]] entry moves each handle
  struct PokeState {
    PokeSpec spec;
    int element = -1;
    Eigen::Vector4d bary;
    int handle = -1;
  };
  std::vector<PokeState> pokes;
  if (sc.mode == "simulate") {
    sim::Material mat{sc.material.young, sc.material.poisson, sc.material.density};
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
    simulator = std::make_unique<sim::Simulator>(m.U, m.T, mat, p);
    for (const ConstraintSpec& c : sc.constraints) {
      const std::vector<int> nodes = select_nodes(c.select, m.U);
      if (c.kind == ConstraintSpec::Kind::Fixed) {
        simulator->fix(nodes);
      } else {
        sim::RigidMotion rm;
        rm.center = c.motion.twist_center;
        rm.axis = c.motion.twist_axis;
        rm.angular_velocity = c.motion.twist_rate;
        rm.velocity = c.motion.velocity;
        rm.start = c.motion.start;
        rm.stop = c.motion.stop;
        simulator->add_kinematic(nodes, rm);
      }
    }
    for (const PokeSpec& ps : sc.pokes) {
      PokeState st;
      st.spec = ps;
      Eigen::MatrixXd q = ps.point.transpose();
      if (ps.relative) {
        const Eigen::RowVector3d lo = m.dense.V.colwise().minCoeff(), hi = m.dense.V.colwise().maxCoeff();
        const Eigen::RowVector3d want = lo + ps.point.transpose().cwiseProduct(hi - lo);
        Eigen::Index best = 0;
        (m.dense.V.rowwise() - want).rowwise().squaredNorm().minCoeff(&best);
        q = m.dense.V.row(best);
      }
      if (ps.target_relative) st.spec.target = *ps.target + q.row(0).transpose();
      const interp::Embedding e = interp::embed(m.U, m.T, q);
      if (!e.outside.empty())
        throw SceneError(sc.file.string() + ": pokes: point (" + format_num(ps.point.x()) + ", " +
                         format_num(ps.point.y()) + ", " + format_num(ps.point.z()) +
                         ") is outside the control mesh");
      st.element = e.element(0);
      st.bary = e.bary.row(0).transpose();
      pokes.push_back(st);
    }
  } else {
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
        if (std::find(drag_vertices.begin(), drag_vertices.end(), v) != drag_vertices.end())
          throw SceneError(sc.file.string() + ": drags[" + std::to_string(k) + "]: control vertex " +
                           std::to_string(v) + " is dragged twice");
        drag_vertices.push_back(v);
        drag_of.push_back(static_cast<int>(k));
      }
    }
    interp::ControlOptions co;
    co.interp = iopt;
    co.mode = sc.interpolation.handles == "soft" ? interp::HandleMode::Soft : interp::HandleMode::Hard;
    handles = std::make_unique<interp::HandleSolver>(m.U, m.T, drag_vertices, co);
    if (sc.interpolation.compare_pinned && !iopt.pin_boundary) {
      co.interp.pin_boundary = true;
      handles_pinned = std::make_unique<interp::HandleSolver>(m.U, m.T, drag_vertices, co);
    }
  }

  metrics["scene"] = sc.name;
  metrics["scene_file"] = sc.file.string();
  metrics["mode"] = sc.mode;
  metrics["dim"] = d;
  metrics["method"] = sc.interpolation.method;
  metrics["alpha"] = solver.alpha();
  metrics["beta"] = solver.beta();
  metrics["pin_boundary"] = sc.interpolation.pin_boundary;
  metrics["dense_vertices"] = m.dense.V.rows();
  metrics["control_vertices"] = m.U.rows();
  metrics["elements"] = m.T.rows();
  metrics["outside_points"] = emb.outside.size();
  metrics["timings_ms"] = {{"load", load_ms}, {"generate", m.generate_seconds * 1e3},
                           {"embed", embed_ms}, {"precompute", precompute_ms}};
  metrics["frames"] = nlohmann::json::array();

  // ---------------------------------------------------------------- frames
  fs::create_directories(res.out_dir);
  Outputs out(sc, m, res.out_dir);
  Eigen::MatrixXd X = m.U, dense, dense_bi, dense_pinned;
  Eigen::MatrixXd X_pinned = m.U;
  double sum_ratio = 0;
  for (int f = 0; f <= frames; ++f) {
    nlohmann::json fr;
    fr["frame"] = f;
    double sim_ms = 0;
    interp::VertexMatrices M, M_pinned;
    // 1. drive the control mesh
    if (simulator) {
      if (f > 0) {
        for (PokeState& p : pokes) {
          if (f == p.spec.first && p.handle < 0) {
            p.handle = p.spec.force ? simulator->add_point_force(p.element, p.bary, *p.spec.force)
                                    : simulator->add_poke(p.element, p.bary, *p.spec.target, p.spec.stiffness);
          }
          if (f > p.spec.last && p.handle >= 0) {
            simulator->remove(p.handle);
            p.handle = -1;
          }
        }
        const sim::StepResult r = simulator->step();
        sim_ms = r.total_ms;
        fr["newton_iterations"] = r.newton_iterations;
        fr["solver_iterations"] = r.solver_iterations;
        if (!r.success) {
          res.failed = true;
          res.message = r.message;
          break;
        }
      }
      X = simulator->positions();
      fr["time"] = simulator->time();
    }
    double solve_ms = 0;
    if (handles) {
      Eigen::MatrixXd targets(static_cast<Eigen::Index>(drag_vertices.size()), d);
      for (size_t k = 0; k < drag_vertices.size(); ++k)
        targets.row(static_cast<Eigen::Index>(k)) =
            m.U.row(drag_vertices[k]) + key_at(sc.drags[static_cast<size_t>(drag_of[k])], f).head(d).transpose();
      t0 = Clock::now();
      X = handles->solve(targets, X);
      M = handles->last_M();
      solve_ms = ms_since(t0);
      if (handles_pinned) {
        X_pinned = handles_pinned->solve(targets, X_pinned);
        M_pinned = handles_pinned->last_M();
      }
    } else {
      t0 = Clock::now();
      M = solver.solve(X);
      solve_ms = ms_since(t0);
    }
    // 2. interpolate
    t0 = Clock::now();
    const interp::VertexMatrices M_out =
        use_bi ? interp::VertexMatrices(interp::VertexMatrices::Zero(M.rows(), M.cols())) : M;
    interp::evaluate<double>(solver.bezier(X, M_out), emb, dense);
    const double interp_ms = ms_since(t0);
    const bool write_now = out.due(f, frames);
    const Eigen::MatrixXd* bi_ptr = nullptr;
    const Eigen::MatrixXd* pin_ptr = nullptr;
    if (write_now && sc.output.image) {
      interp::evaluate<double>(interp::bezier_bi(X, m.T), emb, dense_bi);
      bi_ptr = &dense_bi;
      if (handles_pinned) {
        interp::evaluate<double>(interp::bezier_points(m.U, m.T, X_pinned, M_pinned), emb, dense_pinned);
        pin_ptr = &dense_pinned;
      }
    }
    // 3. metrics (BI against modified-BI at the same control positions)
    const interp::DiscontinuityTable table = interp::discontinuity_table(solver, X, M);
    res.last_table = table;
    fr["sim_ms"] = sim_ms;
    fr["solve_ms"] = solve_ms;
    fr["interp_ms"] = interp_ms;
    fr["disc"] = disc_json(table);
    fr["e_vibr"] = table.e_vibr;
    fr["e_disc"] = table.e_disc;
    if (f > 0 && std::isfinite(table.ratio.mean)) sum_ratio += table.ratio.mean;
    out.frame(f, X, dense, bi_ptr, pin_ptr, write_now);
    metrics["frames"].push_back(fr);
    res.frames = f;
    if (opt.progress) opt.progress(f, frames);
  }
  out.finish();
  metrics["frames_completed"] = res.frames;
  metrics["failure"] = res.failed ? nlohmann::json(res.message) : nlohmann::json(nullptr);
  metrics["last_disc"] = disc_json(res.last_table);
  if (sc.output.metrics) write_text_atomic(res.out_dir / "metrics.json", metrics.dump(1) + "\n");
  return res;
}

}  // namespace mbi::scenes
