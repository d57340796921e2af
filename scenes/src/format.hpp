#pragma once
// Numbers in the runner's messages and names: three significant digits.
#include <cstdio>
#include <string>

namespace mbi::scenes {

inline std::string format_num(double x) {
  char b[64];
  std::snprintf(b, sizeof b, "%.3g", x);
  return b;
}

}  // namespace mbi::scenes
