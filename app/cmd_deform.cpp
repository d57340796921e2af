// mbi deform: the interpolation as a command-line tool, for users with their own simulator.
//
//   mbi deform --control REST --deformed X --mesh DENSE --out OUT [--mesh DENSE2 --out OUT2 ...]
//              [--method bi|modified-bi|phong] [--alpha A] [--pin-boundary] [--stats STATS.json]
//   mbi deform --example twist-bar [--out OUT] [--stats STATS.json]
//   mbi deform --control REST --deformed TRAJECTORY --mesh DENSE --out CACHE|NUMBERED ...
//              (a whole animation: deform_sequence.cpp)
//
// Prints the face discontinuity of BI, Phong and modified-BI side by side, and for --example the
// error of each against the closed-form deformation.
#include "commands.hpp"
#include "deform_outside.hpp"
#include "deform_parts.hpp"
#include "deform_sequence.hpp"
#include "signals.hpp"

#include <mbi/base/timer.hpp>
#include <mbi/generate/procedural.hpp>
#include <mbi/interp.hpp>
#include <mbi/io/atomic_file.hpp>
#include <mbi/io/io.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>
#include <mbi/scenes/limits.hpp>
#include <mbi/scenes/report.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace fs = std::filesystem;

namespace mbi::cli {
namespace {

bool is_point_list(const fs::path& p) {
  const io::FileFormat* f = io::file_format(p);
  return f && f->kind == io::FileKind::points;
}

struct DeformArgs {
  std::string control, deformed, stats, example;
  std::vector<std::string> meshes, outs;  // one --out for each --mesh
  std::string method = pipeline::method_name(pipeline::Method::ModifiedBI);
  double alpha = 0.0;
  bool alpha_given = false;
  bool pin_boundary = false;
  bool force = false;
  std::optional<double> max_outside;
  double fps = 24;
};

SequenceArgs sequence_args(const DeformArgs& a) {
  return {.control = a.control, .deformed = a.deformed, .meshes = a.meshes, .outs = a.outs, .stats = a.stats,
          .method = *pipeline::parse_method(a.method), .alpha = a.alpha_given ? std::optional(a.alpha) : std::nullopt,
          .pin_boundary = a.pin_boundary, .force = a.force, .max_outside = a.max_outside,
          .fps = a.fps};
}

// What the command works on, wherever it came from (files or the built-in example).
struct Problem {
  Eigen::MatrixXd U, X;       // control rest / deformed, n x d
  Eigen::MatrixXi T;          // m x (d+1)
  Eigen::MatrixXd P;          // dense rest points of every part, p x d
  Eigen::MatrixXd P_extra;    // columns beyond d kept as they are (2D control, 3D surface)
  DenseParts dense;           // the dense models, their rows in P
  std::string control_name, deformed_name, mesh_name;
  // The deformation in closed form at the dense points (examples only): p x d and (p d) x d.
  Eigen::MatrixXd exact, exact_gradients;
};

Problem load_files(const DeformArgs& a) {
  Problem pb;
  pb.control_name = a.control;
  pb.deformed_name = a.deformed;
  const io::ControlMesh cm = io::read_control_mesh(a.control);
  pb.U = cm.U;
  pb.T = cm.T;
  const int d = cm.dim();
  for (const std::string& note : cm.notes) std::fprintf(stderr, "mbi deform: note: %s\n", note.c_str());
  pb.X = io::read_positions(a.deformed);
  if (d == 2 && pb.X.cols() == 3) {
    // 2D positions stored with z (a .msh, a .vtk, meshio's 3-column text): one plane, dropped
    if (pb.X.rows() > 0 && (pb.X.col(2).array() != pb.X(0, 2)).any())
      throw std::runtime_error(a.deformed + ": the control mesh is 2D but these positions are not in one plane z = const");
    pb.X.conservativeResize(Eigen::NoChange, 2);
  }
  if (pb.X.rows() != pb.U.rows())
    throw std::runtime_error(a.deformed + ": " + std::to_string(pb.X.rows()) +
                             " deformed positions, but the control mesh " + a.control + " has " +
                             std::to_string(pb.U.rows()) + " vertices");
  if (pb.X.cols() != d)
    throw std::runtime_error(a.deformed + ": positions have " + std::to_string(pb.X.cols()) +
                             " coordinates, but the control mesh " + a.control + " is " +
                             std::to_string(d) + "D");
  pb.dense = read_dense_parts(a.meshes);
  pb.mesh_name = pb.dense.names();
  const Eigen::MatrixXd& P = pb.dense.P;
  if (P.cols() < d)
    throw std::runtime_error(pb.mesh_name + ": points have " + std::to_string(P.cols()) +
                             " coordinates, the control mesh is " + std::to_string(d) + "D");
  pb.P = P.leftCols(d);
  pb.P_extra = P.rightCols(P.cols() - d);
  return pb;
}

Problem load_example(const std::string& name) {
  if (name != "twist-bar")
    throw std::runtime_error("--example: unknown example \"" + name + "\" (known: twist-bar)");
  Problem pb;
  pb.control_name = "built-in paper bar (35 vertices)";
  pb.deformed_name = "built-in twist (90 degrees, mild bend)";
  pb.mesh_name = "built-in bar surface";
  generate::paper_bar_control(pb.U, pb.T);
  io::SurfaceMesh s;
  generate::paper_bar_surface(s.V, s.F);
  pb.P = s.V;
  pb.P_extra.resize(s.V.rows(), 0);
  pb.dense.parts.push_back({.file = pb.mesh_name, .surface = s, .first = 0, .rows = s.V.rows()});
  pb.dense.P = s.V;
  const double pi = std::acos(-1.0);
  pb.X = generate::twist_bend(pb.U, 0.0, 0.0, 0.0, 6.0, pi / 2, 0.05);
  pb.exact = generate::twist_bend(pb.P, 0.0, 0.0, 0.0, 6.0, pi / 2, 0.05);
  pb.exact_gradients = generate::twist_bend_jacobian(pb.P, 0.0, 0.0, 0.0, 6.0, pi / 2, 0.05);
  return pb;
}

// The dense points in the control mesh (a warning for points outside it); embed_ms: its time.
interp::Embedding embed_points(const Problem& pb, double& embed_ms) {
  const auto t0 = Clock::now();
  interp::Embedding emb;
  try {
    emb = interp::embed(pb.U, pb.T, pb.P);
  } catch (const interp::Error& e) {
    throw std::runtime_error(pb.mesh_name + ": " + std::string(e.what()));
  }
  embed_ms = ms_since(t0);
  if (!emb.outside.empty())
    std::fprintf(stderr,
                 "mbi deform: warning: %zu of %d points lie outside the control mesh (farthest "
                 "%.3g); they follow the nearest element by extrapolation\n",
                 emb.outside.size(), emb.size(), emb.max_outside_distance);
  return emb;
}

// What the frame gave, for the statistics and the summary.
struct Result {
  const interp::ModifiedBI* solver = nullptr;  // null: no interior face (one element)
  interp::DiscontinuityTable table;  // BI, Phong and modified-BI
  std::vector<std::pair<std::string, interp::Accuracy>> accuracy;  // --example: BI, Phong, modified-BI
  double embed_ms = 0, precompute_ms = 0, phong_ms = 0, solve_ms = 0, evaluate_ms = 0;
};

// Accuracy of BI, Phong and modified-BI against the closed-form deformation, when it is known
// (--example); empty otherwise.
std::vector<std::pair<std::string, interp::Accuracy>> accuracy_rows(const Problem& pb,
                                                                    pipeline::FramePipeline& pipe) {
  std::vector<std::pair<std::string, interp::Accuracy>> accuracy;
  if (pb.exact.size() == 0) return accuracy;
  const int d = static_cast<int>(pb.U.cols());
  const interp::VertexMatrices Z = interp::VertexMatrices::Zero(pb.U.rows() * d, d);
  for (const auto& [name, M] : {std::pair<std::string, const interp::VertexMatrices*>{"BI", &Z},
                                {"Phong", &pipe.phong_M()},
                                {"modified-BI", &pipe.modified_bi_M()}})
    accuracy.emplace_back(name, interp::accuracy(interp::bezier_points(pb.U, pb.T, pb.X, *M),
                                                 pipe.embedding(), pb.P, pb.exact, pb.exact_gradients));
  return accuracy;
}

nlohmann::json stats_json(const DeformArgs& a, const Problem& pb, const interp::Embedding& embedding,
                          const Result& r) {
  nlohmann::json j;
  j["method"] = a.method;
  j["dim"] = pb.U.cols();
  // without an interior face modified-BI is not built: no alpha, beta or gauge
  j["alpha"] = r.solver ? nlohmann::json(r.solver->alpha()) : nlohmann::json(nullptr);
  j["beta"] = r.solver ? nlohmann::json(r.solver->beta()) : nlohmann::json(nullptr);
  j["pin_boundary"] = a.pin_boundary;
  j["control_vertices"] = pb.U.rows();
  j["elements"] = pb.T.rows();
  j["points"] = pb.P.rows();
  j["outside_points"] = embedding.outside.size();
  j["max_outside_distance"] = embedding.max_outside_distance;
  j["null_space_dim"] = r.solver ? nlohmann::json(r.solver->null_space_dim()) : nlohmann::json(nullptr);
  j["disc"] = scenes::disc_json(r.table, scenes::disc_roundoff(pb.U));
  if (!r.accuracy.empty()) {
    const char* keys[] = {"bi", "phong", "modified_bi"};
    for (size_t k = 0; k < r.accuracy.size(); ++k)
      j["accuracy"][keys[k]] = scenes::accuracy_json(r.accuracy[k].second);
  }
  j["e_vibr"] = r.table.e_vibr;
  j["e_disc"] = r.table.e_disc;
  j["e_total"] = r.table.e_total;
  j["timings_ms"] = {{"embed", r.embed_ms},
                     {"precompute", r.precompute_ms},
                     {"phong_precompute", r.phong_ms},
                     {"solve", r.solve_ms},
                     {"evaluate", r.evaluate_ms}};
  return j;
}

void print_summary(const DeformArgs& a, const Problem& pb, const interp::Embedding& embedding,
                   const Result& r) {
  const int d = static_cast<int>(pb.U.cols());
  std::printf("control: %s: %d vertices, %d %s (%dD)\n", pb.control_name.c_str(),
              static_cast<int>(pb.U.rows()), static_cast<int>(pb.T.rows()),
              d == 3 ? "tetrahedra" : "triangles", d);
  std::printf("dense:   %s: %d points (%zu outside)\n", pb.mesh_name.c_str(),
              static_cast<int>(pb.P.rows()), embedding.outside.size());
  if (r.solver)
    std::printf("method:  %s, alpha %.4g, beta %.4g%s, gauge null space %d\n", a.method.c_str(),
                r.solver->alpha(), r.solver->beta(), a.pin_boundary ? ", boundary pinned" : "",
                r.solver->null_space_dim());
  else
    std::printf("method:  %s (no interior face: modified-BI is not built)\n", a.method.c_str());
  std::printf("\nface discontinuity over %d interior faces (paper Table 2):\n%s", r.table.faces,
              scenes::format_table(r.table, scenes::disc_roundoff(pb.U)).c_str());
  if (!r.accuracy.empty())
    std::printf("\nerror against the closed-form deformation at the %d points (positions relative "
                "to the model size %.4g, gradients relative to |F|):\n%s",
                static_cast<int>(pb.P.rows()), r.accuracy.front().second.size,
                scenes::format_accuracy(r.accuracy).c_str());
  std::printf("E_vibr %.6g  E_disc %.6g  E_total %.6g\n", r.table.e_vibr, r.table.e_disc,
              r.table.e_total);
  std::printf("\ntimes (ms): embed %.2f  precompute %.2f  Phong weights %.2f  solve %.3f  evaluate %.2f\n",
              r.embed_ms, r.precompute_ms, r.phong_ms, r.solve_ms, r.evaluate_ms);
}

// Dense part k of the deformed points (`out`, p x d; `normals` or null) as output i of `outputs`.
// The format follows the extension of `name`; a surface keeps what its file held besides
// positions (write_surface); points alone make a vertices-only surface.
void write_deformed(const io::OutputSet& outputs, std::size_t i, const std::string& name, const Problem& pb,
                    std::size_t k, const Eigen::MatrixXd& out, const Eigen::MatrixXd* normals) {
  const DensePart& part = pb.dense.parts.at(k);
  Eigen::MatrixXd full(part.rows, out.cols() + pb.P_extra.cols());
  full << out.middleRows(part.first, part.rows), pb.P_extra.middleRows(part.first, part.rows);
  if (is_point_list(name)) {
    outputs.write(i, [&](const fs::path& op) { io::write_points(op, full); });
    return;
  }
  if (full.cols() > 3)
    throw std::runtime_error(name + ": points with " + std::to_string(full.cols()) +
                             " coordinates cannot be written as a surface (use .txt/.xyz)");
  io::SurfaceMesh s = part.surface ? *part.surface : io::SurfaceMesh{};
  s.V = Eigen::MatrixXd::Zero(full.rows(), 3);
  s.V.leftCols(full.cols()) = full;
  if (normals && part.has_normals()) s.N = normals->middleRows(part.first, part.rows);
  else s.N.resize(0, 0);
  outputs.write(i, [&](const fs::path& op) { io::write_surface(op, s); });
}

// One overwrite rule for every command: existing outputs only with --force, inputs never (by file
// identity); every output checked and reserved before any work, all written at the end. Returns
// the index of each --out in `outputs`.
std::vector<std::size_t> reserve_outputs(const DeformArgs& a, io::OutputSet& outputs) {
  std::vector<std::size_t> i_outs;
  for (const std::string& out : a.outs) {
    i_outs.push_back(outputs.add(out, "--out"));
    if (!is_point_list(out) && !io::is_surface_file(out))
      throw std::runtime_error("--out " + out + ": unknown output format '" + io::lower_extension(out) + "' (expected " +
                               io::extensions_of(io::FileKind::surface) + ", .txt or .xyz)");
  }
  return i_outs;
}

std::vector<fs::path> input_files(const DeformArgs& a) {
  std::vector<fs::path> inputs{a.control, a.deformed};
  inputs.insert(inputs.end(), a.meshes.begin(), a.meshes.end());
  for (const fs::path& p : io::control_mesh_files(a.control)) inputs.push_back(p);
  return inputs;
}

void check_required(const DeformArgs& a) {
  for (const auto& [flag, v] : {std::pair{"--control", &a.control}, {"--deformed", &a.deformed}})
    if (v->empty()) throw std::runtime_error(std::string(flag) + " is required (or use --example)");
  if (a.meshes.empty()) throw std::runtime_error("--mesh is required (or use --example)");
  if (a.outs.empty()) throw std::runtime_error("--out is required (or use --example)");
  if (a.outs.size() != a.meshes.size())
    throw std::runtime_error(std::to_string(a.meshes.size()) + " --mesh but " + std::to_string(a.outs.size()) +
                             " --out: give one --out for each --mesh, in the same order");
}

int run_deform(const DeformArgs& a) {
  const bool example = !a.example.empty();
  if (!example) check_required(a);
  if (!example && is_sequence(a.deformed, a.outs)) return run_deform_sequence(sequence_args(a));
  handle_interrupts(nullptr);  // all or nothing: a signal ends it at once, no temporaries
  io::OutputSet outputs(example ? std::vector<fs::path>() : input_files(a), a.force);
  const std::vector<std::size_t> i_outs = reserve_outputs(a, outputs);
  const std::size_t i_stats = a.stats.empty() ? 0 : outputs.add(a.stats, "--stats");
  if (example && a.outs.size() > 1) throw std::runtime_error("--example writes one --out");
  if (a.alpha_given) check_option("--alpha", [&] { interp::check_alpha(a.alpha); });

  Problem pb = example ? load_example(a.example) : load_files(a);
  const int d = static_cast<int>(pb.U.cols());
  // the same caps as a scene, before the embedding and the precompute allocate (docs/limits.md)
  scenes::check_run_size(pb.control_name, pb.P.rows(), pb.U.rows(), pb.T.rows(), d);
  if (!pb.X.allFinite()) throw std::runtime_error(pb.deformed_name + ": non-finite position");

  double embed_ms = 0;
  interp::Embedding emb = embed_points(pb, embed_ms);
  if (a.max_outside) refuse_far_points(emb, pb.U, pb.T, pb.P, *a.max_outside, pb.mesh_name, pb.control_name);

  // One frame through the pipeline: the given positions drive it, BI skips the solve.
  pipeline::PipelineOptions po;
  po.method = *pipeline::parse_method(a.method);
  // A 3D surface with normals gets deformed normals (the file's normals are the rest normals).
  Eigen::MatrixXd rest_normals;
  if (d == 3) rest_normals = pb.dense.normals();  // when a part has normals
  po.normals = rest_normals.rows() > 0;
  if (a.alpha_given) po.interp.alpha = a.alpha;
  po.interp.pin_boundary = a.pin_boundary;
  // One element has no interior face: BI and Phong need none; modified-BI minimises the
  // discontinuity across interior faces and needs at least one.
  const bool has_faces = interp::interior_faces(pb.T).rows() > 0;
  if (!has_faces && po.method == pipeline::Method::ModifiedBI)
    throw std::runtime_error(pb.control_name + ": the control mesh has no interior face (one element); "
                             "modified-BI minimises the discontinuity across interior faces and needs at "
                             "least two face-adjacent elements (--method bi or phong take it)");
  auto given = std::make_unique<pipeline::GivenDriver>(pb.U);
  given->set(pb.X);
  std::optional<pipeline::FramePipeline> pipe;
  const interp::ModifiedBI* solver = nullptr;
  try {
    pipe.emplace(pb.U, pb.T, std::move(emb), std::move(given), po,
                 std::make_unique<pipeline::CpuEvaluator>(pipeline::Precision::Double),
                 rest_normals);
    // the comparison table needs modified-BI, where there is an interior face to compare
    if (has_faces) solver = &pipe->solver();
  } catch (const interp::Error& e) {
    throw std::runtime_error(pb.control_name + ": " + std::string(e.what()));
  }
  const pipeline::FrameResult fr = pipe->step();
  if (!fr.ok) throw std::runtime_error(fr.message);
  const Eigen::MatrixXd& out = pipe->positions();
  Result r;
  r.solver = solver;
  r.embed_ms = embed_ms;
  r.precompute_ms = pipe->precompute_ms();
  r.solve_ms = pipe->timings().solve_ms;
  r.evaluate_ms = pipe->timings().bezier_ms + pipe->timings().evaluate_ms;
  if (!out.allFinite()) throw std::runtime_error("evaluation produced non-finite positions");

  // BI, Phong and modified-BI side by side, whatever the method
  if (solver) {
    r.table = interp::discontinuity_table(*solver, pb.X, pipe->modified_bi_M(), pipe->phong_M());
  } else {  // no face to measure: every column 0 over 0 faces
    r.table.phong = interp::Summary{};
  }
  r.accuracy = accuracy_rows(pb, *pipe);
  r.phong_ms = pipe->phong_precompute_ms();
  const interp::Embedding& embedding = pipe->embedding();

  // Outputs: nothing is written unless everything above succeeded.
  for (std::size_t k = 0; k < a.outs.size(); ++k)
    write_deformed(outputs, i_outs[k], a.outs[k], pb, k, out, po.normals ? &pipe->normals() : nullptr);
  if (!a.stats.empty()) {
    const nlohmann::json j = stats_json(a, pb, embedding, r);
    check_finite(j, a.stats);
    outputs.write(i_stats, [&](const fs::path& p) { io::write_text_atomic(p, j.dump(2) + "\n"); });
  }
  outputs.commit();
  print_summary(a, pb, embedding, r);
  for (const std::string& o : a.outs) std::printf("wrote %s\n", o.c_str());
  return 0;
}

const Registrar reg{
    "deform", "Deform a dense mesh by a deformed control mesh (modified-BI, Phong or BI)",
    [](CLI::App& sub) -> Action {
      auto a = std::make_shared<DeformArgs>();
      sub.add_option("--control", a->control,
                     "REQUIRED (unless --example) rest control mesh: TetGen .node/.ele (or base name), Gmsh .msh "
                     "or legacy VTK .vtk");
      sub.add_option("--deformed", a->deformed,
                     "REQUIRED (unless --example) deformed control positions, one per control node in file order: "
                     ".node, .msh, .vtk, .vtu or plain text (n lines of d numbers); or a whole trajectory: .pc2, .mdd, "
                     ".pvd, numbered files x_%04d.vtk or a quoted glob 'x_*.vtk'");
      sub.add_option("--mesh", a->meshes,
                     "REQUIRED (unless --example) dense model: .obj/.ply/.off/.stl/.glb/.gltf, or points .txt/.xyz; "
                     "repeat it for several models driven by one control mesh, each with its --out");
      sub.add_option("--out", a->outs,
                     "REQUIRED (unless --example) output of each --mesh, format by extension: .obj/.ply/.off/.stl/.glb/"
                     ".gltf (keeping the input's attributes when the format is the same) or points .txt/.xyz; for a "
                     "trajectory a point cache .pc2/.mdd, an animated glTF .glb/.gltf or numbered files out_%04d.obj");
      sub.add_option("--method", a->method, "interpolation")
          ->check(CLI::IsMember(pipeline::kMethodNames.names()));
      sub.add_option_function<double>(
          "--alpha",
          [a](double v) {
            a->alpha = v;
            a->alpha_given = true;
          },
          "weight of E_vibr (> 0; default 0.1 in 3D, 0.2 in 2D)");
      sub.add_flag("--pin-boundary", a->pin_boundary, "M = 0 on the control mesh boundary");
      sub.add_option("--stats", a->stats, "write statistics and timings as JSON");
      sub.add_option("--max-outside", a->max_outside,
                     "refuse dense points farther outside the control mesh than this times the model size")
          ->check(CLI::NonNegativeNumber);
      sub.add_option_function<std::string>(
          "--fps",
          [a](const std::string& s) {
            try {
              a->fps = parse_fps(s);
            } catch (const std::runtime_error& e) {
              throw CLI::ValidationError(e.what());
            }
          },
          "frames per second where times meet frames (MDD times, PC2 frames; default 24)");
      sub.add_flag("--force", a->force, "overwrite existing --out / --stats files");
      sub.add_option("--example", a->example, "built-in example instead of files: twist-bar");
      add_threads_option(sub);
      return [a] { return run_deform(*a); };
    }};

}  // namespace
}  // namespace mbi::cli
