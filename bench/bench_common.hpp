#pragma once
// Shared set-up of mbi-bench (scripts/bench.sh writes the report from its JSON): the run mode,
// box control meshes, point clouds embedded in them and the headless GL context, each built
// once per process and cached (inline functions: one instance across the bench/*.cpp files).
//
// MBI_BENCH_QUICK=1 (scripts/bench.sh --quick, CI): small sizes and short measuring times, so
// that every benchmark still runs and the report still builds, in well under a minute.
// MBI_BENCH_THREADS=N runs the library on N threads.
#include <mbi/generate/procedural.hpp>
#include <mbi/gpu/context.hpp>
#include <mbi/interp.hpp>
#include <mbi/interp/threads.hpp>

#include <cstdlib>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <tuple>
#include <vector>

namespace mbi::bench {

/// MBI_BENCH_THREADS=N: the library's thread count for the whole run (mbi::interp::set_threads).
[[maybe_unused]] inline const bool threads_set = [] {
  const char* v = std::getenv("MBI_BENCH_THREADS");
  if (v && *v) interp::set_threads(std::atoi(v));
  return true;
}();

inline bool quick() {
  static const bool q = [] {
    const char* v = std::getenv("MBI_BENCH_QUICK");
    return v != nullptr && *v != '\0' && std::string(v) != "0";
  }();
  return q;
}

/// Minimum measuring time of one benchmark (s): `full` in the full run, 0.01 s in quick mode.
inline double min_time(double full = 0.2) { return quick() ? 0.01 : full; }

/// Dense point counts of the throughput benchmarks.
inline std::vector<long long> point_counts() {
  if (quick()) return {35000};
  return {35000, 250000, 1000000, 4000000};
}

/// A box control mesh (cell size 1, cells nx x ny x nz, 6 tetrahedra per cell), its twisted and
/// bent deformed pose X, and the element Bezier points of that pose for BI and modified-BI
/// (alpha 0.1, automatic beta and solve path).
struct Cage {
  Eigen::MatrixXd U, X;
  Eigen::MatrixXi T;
  interp::BezierPoints bezier_bi, bezier_mbi;
  interp::VertexMatrices M;  ///< modified-BI's M at X
};

/// Cells of the box cages by their control-vertex count: 100 -> 4x4x3 cells (100 vertices, 288
/// tetrahedra), 450 -> 7x7x6 (448 vertices, 1,764 tetrahedra).
inline Eigen::Vector3i cage_cells(int control) {
  return control <= 100 ? Eigen::Vector3i(4, 4, 3) : Eigen::Vector3i(7, 7, 6);
}

inline const Cage& box_cage(int control) {
  static std::map<int, std::unique_ptr<Cage>> cache;
  auto& slot = cache[control];
  if (slot) return *slot;
  slot = std::make_unique<Cage>();
  Cage& c = *slot;
  const Eigen::Vector3i n = cage_cells(control);
  generate::box_tets(Eigen::Vector3d::Zero(), n.cast<double>(), n, c.U, c.T);
  c.X = generate::twist_bend(c.U, 0.5 * n.x(), 0.5 * n.y(), 0, n.z(), 1.2, 0.1);
  c.bezier_bi = interp::bezier_bi(c.X, c.T);
  const interp::ModifiedBI solver(c.U, c.T);
  c.M = solver.solve(c.X);
  c.bezier_mbi = solver.bezier(c.X, c.M);
  return c;
}

/// p points uniformly random in a box cage (seeded, so every run measures the same points),
/// embedded once; unit rest normals (direction from the box centre) in double and float.
struct Cloud {
  Eigen::MatrixXd P;  ///< p x 3 rest points
  interp::Embedding emb;
  Eigen::MatrixXd normals;
  Eigen::MatrixXf normals_f;
};

inline const Cloud& cloud(int control, long long points) {
  static std::map<std::pair<int, long long>, std::unique_ptr<Cloud>> cache;
  auto& slot = cache[{control, points}];
  if (slot) return *slot;
  slot = std::make_unique<Cloud>();
  Cloud& c = *slot;
  const Cage& cage = box_cage(control);
  const Eigen::Vector3d hi = cage_cells(control).cast<double>();
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> uni(0.001, 0.999);
  c.P.resize(points, 3);
  c.normals.resize(points, 3);
  for (long long i = 0; i < points; ++i) {
    const Eigen::RowVector3d q(hi.x() * uni(rng), hi.y() * uni(rng), hi.z() * uni(rng));
    c.P.row(i) = q;
    c.normals.row(i) = (q - 0.5 * hi.transpose()).normalized();
  }
  c.normals_f = c.normals.cast<float>();
  c.emb = interp::embed(cage.U, cage.T, c.P);
  return c;
}

/// The headless GL context (Mesa llvmpipe without a GPU), made once; nullptr with the reason in
/// `why` when there is none (the GPU benchmarks then report it and are skipped).
inline gpu::Context* gl_context(std::string& why) {
  static std::unique_ptr<gpu::Context> c;
  static std::string error;
  if (!c && error.empty()) {
    try {
      c = gpu::Context::headless();
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
  why = error;
  return c.get();
}

}  // namespace mbi::bench
