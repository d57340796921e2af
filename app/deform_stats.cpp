// mbi deform's statistics: BI, Phong and modified-BI side by side at the last frame, the summary
// on stdout and --stats (deform.hpp).
#include "deform.hpp"

#include <mbi/base/timer.hpp>
#include <mbi/error.hpp>
#include <mbi/interp.hpp>
#include <mbi/pipeline/precompute.hpp>
#include <mbi/scenes/report.hpp>

#include <algorithm>
#include <cstdio>
#include <stdexcept>

namespace mbi::cli {
namespace {

using AccuracyRows = std::vector<std::pair<std::string, interp::Accuracy>>;

// Accuracy of BI, Phong and modified-BI (M 0, M_phong, M_mbi) against the closed form.
AccuracyRows accuracy_rows(const Model& m, const pipeline::Deformer& deformer, const Eigen::MatrixXd& X,
                           const interp::VertexMatrices& M_phong, const interp::VertexMatrices& M_mbi) {
  AccuracyRows rows;
  const int d = m.dim();
  const interp::VertexMatrices Z = interp::VertexMatrices::Zero(m.U.rows() * d, d);
  for (const auto& [name, M] : {std::pair<std::string, const interp::VertexMatrices*>{"BI", &Z},
                                {"Phong", &M_phong},
                                {"modified-BI", &M_mbi}})
    rows.emplace_back(name, interp::accuracy(interp::bezier_points(m.U, m.T, X, *M), deformer.embedding(), m.P,
                                             m.exact, m.exact_gradients));
  return rows;
}

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

}  // namespace

Comparison compare_methods(const Model& m, const pipeline::Deformer& deformer, Run& run) {
  Comparison c;
  if (interp::interior_faces(m.T).rows() == 0) {  // no face to measure: every column 0 over 0 faces
    c.table.phong = interp::Summary{};
    return c;
  }
  // the deformer's own precompute where its method has one; the others built here
  std::optional<pipeline::Precompute> own;
  const interp::ModifiedBI* solver = nullptr;
  const interp::Phong* phong = nullptr;
  try {
    own.emplace(m.U, m.T, pipeline::Method::BI, deformer.options().interp);
    solver = deformer.method() == pipeline::Method::ModifiedBI ? &deformer.solver() : &own->solver();
    phong = deformer.method() == pipeline::Method::Phong ? &deformer.phong() : &own->phong();
  } catch (const mbi::Error& e) {
    throw std::runtime_error(m.control_name + ": " + e.what());
  }
  run.precompute_ms += own->precompute_ms();
  run.phong_ms += own->phong_ms();
  const Eigen::MatrixXd& X = run.last_pose;
  const auto t_solve = Clock::now();
  const interp::VertexMatrices M_mbi = solver->solve(X);
  run.solve_ms = ms_since(t_solve);
  const interp::VertexMatrices M_phong = phong->M(X);
  c.factorization = solver->factorization();
  c.factor_nonzeros = solver->factor_nonzeros();
  c.factor_stored_values = solver->factor_stored_values();
  c.factor_index_bytes = solver->factor_index_bytes();
  c.kept_bytes = solver->memory_bytes();
  c.dense_operator = solver->dense_operator();
  c.table = interp::discontinuity_table(*solver, X, M_mbi, M_phong);
  c.built = true;
  c.alpha = solver->alpha();
  c.beta = solver->beta();
  c.null_space_dim = solver->null_space_dim();
  if (m.exact.size() > 0) c.accuracy = accuracy_rows(m, deformer, X, M_phong, M_mbi);
  return c;
}

nlohmann::json stats_json(const DeformArgs& a, const Model& m, const pipeline::Deformer& deformer, const Run& run,
                          const std::optional<Comparison>& c) {
  nlohmann::json j;
  const bool built = c && c->built;  // else no alpha, beta or gauge
  j["method"] = pipeline::method_name(a.method);
  j["dim"] = m.dim();
  j["alpha"] = built ? nlohmann::json(c->alpha) : nlohmann::json(nullptr);
  j["beta"] = built ? nlohmann::json(c->beta) : nlohmann::json(nullptr);
  j["pin_boundary"] = a.pin_boundary;
  j["control_vertices"] = m.U.rows();
  j["elements"] = m.T.rows();
  j["points"] = m.P.rows();
  j["outside_points"] = deformer.embedding().outside.size();
  j["max_outside_distance"] = deformer.embedding().max_outside_distance;
  j["null_space_dim"] = built ? nlohmann::json(c->null_space_dim) : nlohmann::json(nullptr);
  if (c) {
    j["disc"] = scenes::disc_json(c->table, scenes::disc_roundoff(m.U));
    const char* keys[] = {"bi", "phong", "modified_bi"};
    for (std::size_t k = 0; k < c->accuracy.size(); ++k) j["accuracy"][keys[k]] = scenes::accuracy_json(c->accuracy[k].second);
    j["e_vibr"] = c->table.e_vibr;
    j["e_disc"] = c->table.e_disc;
    j["e_total"] = c->table.e_total;
  }
  if (built)
    j["factor"] = {{"factorization", c->factorization}, {"nonzeros", c->factor_nonzeros},
                   {"stored_values", c->factor_stored_values}, {"index_bytes", c->factor_index_bytes},
                   {"kept_bytes", c->kept_bytes}, {"dense_operator", c->dense_operator}};
  j["memory_estimate"] = {{"peak_bytes", run.estimate.peak_bytes},         {"factor_bytes", run.estimate.factor_bytes},
                          {"factor_nonzeros", run.estimate.factor_nonzeros}, {"assembly_bytes", run.estimate.assembly_bytes},
                          {"model_bytes", run.estimate.model_bytes},         {"ordering", run.estimate.ordering},
                          {"unknowns", run.estimate.unknowns},               {"factor_flops", run.estimate.factor_flops}};
  j["frames"] = run.done;
  j["frames_in_trajectory"] = run.frames;
  if (!run.failure.empty()) j["failure"] = run.failure;
  if (run.signal) j["interrupted_by_signal"] = run.signal;
  const double n = std::max(run.done, 1);
  j["timings_ms"] = {{"embed", run.embed_ms},      {"precompute", run.precompute_ms},
                     {"phong_precompute", run.phong_ms}, {"read", run.read_ms},
                     {"memory_estimate", run.estimate_ms}, {"solve", run.solve_ms},
                     {"deform", run.deform_ms},    {"write", run.write_ms},
                     {"read_per_frame", run.read_ms / n}, {"deform_per_frame", run.deform_ms / n},
                     {"write_per_frame", run.write_ms / n}};
  return j;
}

void print_summary(const DeformArgs& a, const Model& m, const pipeline::Deformer& deformer, const Run& run,
                   const std::optional<Comparison>& c) {
  const int d = m.dim();
  const char* method = pipeline::method_name(a.method);
  std::printf("control: %s: %d vertices, %d %s (%dD)\n", m.control_name.c_str(), static_cast<int>(m.U.rows()),
              static_cast<int>(m.T.rows()), d == 3 ? "tetrahedra" : "triangles", d);
  std::printf("dense:   %s: %d points (%zu outside)\n", m.mesh_name.c_str(), static_cast<int>(m.P.rows()),
              deformer.embedding().outside.size());
  if (c && c->built)
    std::printf("method:  %s, alpha %.4g, beta %.4g%s, gauge null space %d\n", method, c->alpha, c->beta,
                a.pin_boundary ? ", boundary pinned" : "", c->null_space_dim);
  else
    std::printf("method:  %s%s\n", method, c ? " (no interior face: modified-BI is not built)" : "");
  if (run.trajectory)
    std::printf("frames:  %d of %d from %s into %s\n", run.done, run.frames, a.deformed.c_str(), joined(a.outs).c_str());
  if (c) {
    std::printf("\nface discontinuity over %d interior faces (paper Table 2%s):\n%s", c->table.faces,
                run.trajectory ? ", the last frame" : "", scenes::format_table(c->table, scenes::disc_roundoff(m.U)).c_str());
    if (!c->accuracy.empty())
      std::printf("\nerror against the closed-form deformation at the %d points (positions relative "
                  "to the model size %.4g, gradients relative to |F|):\n%s",
                  static_cast<int>(m.P.rows()), c->accuracy.front().second.size, scenes::format_accuracy(c->accuracy).c_str());
    std::printf("E_vibr %.6g  E_disc %.6g  E_total %.6g\n", c->table.e_vibr, c->table.e_disc, c->table.e_total);
  }
  const double n = std::max(run.done, 1);
  std::printf("\ntimes (ms): embed %.2f  precompute %.2f  Phong weights %.2f  %sread %.3f  deform %.3f  write %.3f\n",
              run.embed_ms, run.precompute_ms, run.phong_ms, run.trajectory ? "per frame: " : "", run.read_ms / n,
              run.deform_ms / n, run.write_ms / n);
}

}  // namespace mbi::cli
