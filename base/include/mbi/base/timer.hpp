#pragma once
// The one wall clock of mbi's timings (per-phase times, metrics, reports): steady, in ms.
#include <chrono>

namespace mbi {

using Clock = std::chrono::steady_clock;

/// Milliseconds elapsed since t0.
inline double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

}  // namespace mbi
