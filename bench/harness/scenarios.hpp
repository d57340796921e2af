#pragma once
// The harness's scenarios: what an application does with mbi, timed with the installed library.
// Each adds rows to a Report (main.cpp writes them as JSON and prints them).
#include "cages.hpp"
#include "loads.hpp"

#include <mbi/interp.hpp>

#include <memory>
#include <string>
#include <vector>

namespace harness {

namespace interp = mbi::interp;

struct Row {
  std::string scenario, name, load;  ///< e.g. "loaded", "solve 1331", "thread"
  double ms = 0;                     ///< median time
  int samples = 0;
  std::string note;                  ///< a ratio or a count, as text
  double mean_ms = 0;                ///< mean time (0: not recorded)
};

struct Report {
  std::vector<Row> rows;
  void add(Row r);
};

/// Geometry and solvers shared by the scenarios, built once: the 448- and 1,331-vertex cages,
/// their precomputes, `points` random points embedded in the 448 cage and their FastEvaluator.
struct Context {
  Cage c448, c1331;
  Eigen::MatrixXd X448, X1331;  ///< a deformed pose of each
  interp::Embedding emb;
  std::unique_ptr<interp::ModifiedBI> mbi448, mbi1331;
  std::unique_ptr<interp::FastEvaluator> fast;
  int reps = 1;  ///< rounds of each measurement (more: steadier medians)
  explicit Context(long long points, int reps);
};

/// Interleaved frame loop (solve, Bezier, fast evaluation) against the same phases timed alone,
/// warm and after a 64 MB sweep of the cache (what the other phases leave behind).
void frame_loop(Context& c, Report& r);
/// The first solve right after a precompute (1,331 vertices) against the solves after it, in a
/// process that also evaluates the points.
void first_solve(Context& c, Report& r);
/// Every stage quiet and beside each load.
void loaded(Context& c, Report& r, const std::vector<Load>& loads);
/// interp::evaluate<float> (one-shot) against FastEvaluator and a plain 1-thread double BI loop.
void one_shot(Context& c, Report& r);
/// Two caller threads, each with objects of its own, running frames at once: frame time and the
/// threads of the process against one caller.
void callers(Context& c, Report& r);

}  // namespace harness
