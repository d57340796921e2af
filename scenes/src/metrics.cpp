#include "metrics.hpp"

#include <mbi/base/timer.hpp>
#include <mbi/io/atomic_file.hpp>
#include <mbi/scenes/report.hpp>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace mbi::scenes {
namespace {

// `text` with `spaces` more spaces before each line: a record as it sits in the frames array.
std::string indented(const std::string& text, int spaces) {
  const std::string pad(static_cast<std::size_t>(spaces), ' ');
  std::string out = pad;
  for (char c : text) {
    out += c;
    if (c == '\n') out += pad;
  }
  return out;
}

// The contact points of a surface contact: its points at the rest pose U (n x 3), counted.
Eigen::Index contact_point_count(const pipeline::SurfaceContact& c, const Eigen::MatrixXd& U) {
  const Eigen::MatrixXd Ut = U.transpose();
  return c.points(Eigen::Map<const Eigen::VectorXd>(Ut.data(), Ut.size())).rows();
}

}  // namespace

long resident_kb() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return -1;
  long size = 0, resident = -1;
  if (std::fscanf(f, "%ld %ld", &size, &resident) != 2) resident = -1;
  std::fclose(f);
  const long page = ::sysconf(_SC_PAGESIZE);
  return resident < 0 || page <= 0 ? -1 : resident * (page / 1024);
}

RunMetrics::RunMetrics(const Scene& sc, const SceneModels& m, pipeline::FramePipeline& pipe,
                       std::size_t outside_points, const char* renderer, double load_ms, double embed_ms,
                       const std::filesystem::path& dir)
    : pipe_(pipe),
      sim_(dynamic_cast<const pipeline::SimulatorDriver*>(&pipe.driver())),
      roundoff_(disc_roundoff(m.U)),
      dir_(dir),
      keep_records_(sc.output.metrics) {
  const interp::ModifiedBI& solver = pipe.solver();
  json_["scene"] = sc.name;
  json_["scene_file"] = sc.file.string();
  json_["mode"] = mode_name(sc.mode);
  json_["dim"] = m.dim();
  json_["method"] = pipeline::method_name(sc.interpolation.method);
  json_["alpha"] = solver.alpha();
  json_["beta"] = solver.beta();
  json_["pin_boundary"] = sc.interpolation.options.pin_boundary;
  json_["dense_vertices"] = m.dense.V.rows();
  json_["control_vertices"] = m.U.rows();
  json_["elements"] = m.T.rows();
  json_["outside_points"] = outside_points;
  json_["evaluator"] = pipe.evaluator().name();
  json_["renderer"] = renderer;
  json_["timings_ms"] = {{"load", load_ms}, {"generate", m.generate_seconds * 1e3},
                         {"embed", embed_ms}, {"precompute", pipe.precompute_ms()}};
  if (pipe.method() == pipeline::Method::Phong)
    json_["timings_ms"]["phong_precompute"] = pipe.phong_precompute_ms();
  if (sim_ && sim_->contact()) {  // contact = surface only: a control scene's keys stay as they were
    const pipeline::SurfaceContact& c = *sim_->contact();
    json_["contact"] = {{"mode", pipeline::kContactModeNames.name(pipeline::ContactMode::Surface)},
                        {"points", contact_point_count(c, m.U)},
                        {"colliders", c.colliders().size()},
                        {"stiffness", c.stiffness()},
                        {"newton_iterations", sim_->simulator().params().newton_iterations},
                        {"newton_tolerance", sim_->simulator().params().newton_tolerance}};
  }
}

nlohmann::json RunMetrics::start_frame(int f) const {
  nlohmann::json record;
  record["frame"] = f;
  if (sim_) {
    record["time"] = sim_->simulator().time();
    record["newton_iterations"] = f > 0 ? sim_->last_step().newton_iterations : 0;
    record["solver_iterations"] = f > 0 ? sim_->last_step().solver_iterations : 0;
    if (sim_->contact()) {
      record["contact_points"] = sim_->touching_points();
      record["line_search_halvings"] = f > 0 ? sim_->last_step().line_search_halvings : 0;
    }
  }
  return record;
}

void RunMetrics::add_timings(nlohmann::json& record, int f) {
  const pipeline::FrameTimings& tm = pipe_.timings();
  record["sim_ms"] = sim_ && f > 0 ? sim_->last_step().total_ms : 0.0;
  record["drive_ms"] = tm.drive_ms;
  record["solve_ms"] = tm.solve_ms + (sim_ ? 0.0 : tm.drive_ms);  // handles: the joint solve
  record["bezier_ms"] = tm.bezier_ms;
  record["interp_ms"] = tm.bezier_ms + tm.evaluate_ms;
  record["upload_ms"] = pipe_.evaluator().timings().upload_ms;
  record["pass_ms"] = pipe_.evaluator().timings().pass_ms;
}

interp::DiscontinuityTable RunMetrics::table() {
  const interp::ModifiedBI& solver = pipe_.solver();
  return pipe_.method() == pipeline::Method::Phong
             ? interp::discontinuity_table(solver, pipe_.control_positions(), pipe_.modified_bi_M(),
                                           pipe_.phong_M())
             : interp::discontinuity_table(solver, pipe_.control_positions(), pipe_.modified_bi_M());
}

interp::DiscontinuityTable RunMetrics::add_discontinuity(nlohmann::json& record) {
  const auto t0 = Clock::now();
  interp::DiscontinuityTable t;
  try {
    t = table();
  } catch (const interp::OverflowError& e) {  // a run error (exit 3), not a library one
    throw Error(e.what());
  }
  record["disc"] = disc_json(t, roundoff_);  // throws on a non-finite value
  if (!std::isfinite(t.e_vibr) || !std::isfinite(t.e_disc))
    throw Error("E_vibr or E_disc is not finite");
  record["e_vibr"] = t.e_vibr;
  record["e_disc"] = t.e_disc;
  record["metrics_ms"] = ms_since(t0);
  return t;
}

void RunMetrics::add_frame(nlohmann::json record) {
  record["rss_kb"] = resident_kb();
  if (keep_records_) {
    if (!records_) records_ = std::make_unique<io::ScratchFile>(dir_, "metrics.json");
    const std::string text = (frames_ > 0 ? ",\n" : "") + indented(record.dump(1), 2);
    const long at = records_->size();
    records_->append(text.data(), text.size());
    last_at_ = at;
  }
  before_last_ = std::move(last_);
  last_ = std::move(record);
  ++frames_;
}

void RunMetrics::discard_last() {
  if (frames_ == 0) return;
  if (records_) records_->truncate(last_at_);
  last_ = std::move(before_last_);
  before_last_ = nullptr;
  --frames_;
}

void RunMetrics::finish(const RunResult& res, double pictures_ms) {
  json_["timings_ms"]["pictures"] = pictures_ms;
  json_["frames_completed"] = res.frames;
  json_["failure"] = res.failed ? nlohmann::json(res.message) : nlohmann::json(nullptr);
  json_["interrupted"] = res.interrupted ? nlohmann::json(signal_name(res.interrupted)) : nlohmann::json(nullptr);
  const bool has_disc = frames_ > 0 && last_.contains("disc");
  json_["last_disc"] = has_disc      ? last_["disc"]
                       : frames_ == 0 ? nlohmann::json(nullptr)
                                      : disc_json(res.last_table, roundoff_);
}

void RunMetrics::write() const {
  // json_ dumped with an empty frames array, the records put in its place from the scratch file
  nlohmann::json top = json_;
  top["frames"] = nlohmann::json::array();
  const std::string text = top.dump(1), empty = "\n \"frames\": []";
  const std::size_t at = text.find(empty);
  io::write_file_atomic(dir_ / "metrics.json", [&](io::AtomicFile& f) {
    f.write(text.substr(0, at));
    if (!records_ || records_->size() == 0) {
      f.write(empty);
    } else {
      f.write("\n \"frames\": [\n");
      std::vector<char> chunk(1 << 20);
      for (long done = 0; done < records_->size();) {
        const auto n = static_cast<std::size_t>(std::min<long>(records_->size() - done, static_cast<long>(chunk.size())));
        records_->read(done, chunk.data(), n);
        f.write(chunk.data(), n);
        done += static_cast<long>(n);
      }
      f.write("\n ]");
    }
    f.write(text.substr(at + empty.size()) + "\n");
  });
}

}  // namespace mbi::scenes
