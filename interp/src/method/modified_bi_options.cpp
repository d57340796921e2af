// modified-BI's option checks: one small file, so that readers of options (the scene parser,
// its fuzz target) link them without the solver.
#include <mbi/interp/modified_bi.hpp>

#include <cmath>
#include <string>

namespace mbi::interp {

double default_alpha(int d) {
  if (d == 3) return 0.1;
  if (d == 2) return 0.2;
  throw Error("dimension must be 2 or 3, got " + std::to_string(d));
}

double check_alpha(double alpha) {
  if (!(alpha > 0) || !std::isfinite(alpha)) throw Error("alpha must be a finite number > 0, got " + std::to_string(alpha));
  return alpha;
}

double resolve_alpha(const Options& options, int d) {
  return options.alpha ? check_alpha(*options.alpha) : default_alpha(d);
}

void check_beta(const Options& options) {
  if (!(options.beta >= 0) || !std::isfinite(options.beta))
    throw Error("beta must be > 0 (0 selects the automatic rule), got " + std::to_string(options.beta));
}

void check_max_memory(const Options& options) {
  if (!(options.max_memory >= 0) || !std::isfinite(options.max_memory))
    throw Error("max_memory must be a finite number of bytes >= 0 (0: the memory available), got " +
                std::to_string(options.max_memory));
}

}  // namespace mbi::interp
