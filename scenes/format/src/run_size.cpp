// A run's memory estimate against the memory it may take (see mbi/scenes/limits.hpp).
#include <mbi/scenes/limits.hpp>
#include <mbi/scenes/scene.hpp>

#include <mbi/interp/system_memory.hpp>

namespace mbi::scenes {

interp::MemoryEstimate check_run_size(const std::string& where, long long dense_vertices, const Eigen::MatrixXd& U,
                                      const Eigen::MatrixXi& T, const interp::Options& options,
                                      bool simulation) {
  interp::MemoryEstimate e;
  try {
    e = interp::estimate_memory(U, T, dense_vertices, options);
  } catch (const mbi::Error& err) {  // a size the estimate itself cannot take: named where it came from
    throw Error(where + ": " + err.what());
  }
  if (simulation) {  // the simulator's 12 x 12 (2D: 6 x 6) blocks of each element, as triplets
    const double block = static_cast<double>((U.cols() + 1) * U.cols());
    e.peak_bytes += static_cast<double>(T.rows()) * block * block * 16.0;
  }
  std::string name;
  const double limit = interp::memory_limit(options.max_memory, name);
  interp::check_memory(e, limit, name, where);
  return e;
}

}  // namespace mbi::scenes
