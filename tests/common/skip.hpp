#pragma once
// Skipping a test that cannot run here (Catch2 v2 has no SKIP): the test process exits with
// MBI_SKIP_CODE, which CTest's SKIP_RETURN_CODE (tests/CMakeLists.txt) reports as "Skipped".
// CTest runs each test case in its own process, so exiting ends only this case.
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#ifndef MBI_SKIP_CODE
#define MBI_SKIP_CODE 77
#endif

namespace mbi::test {

[[noreturn]] inline void skip(const char* why) {
  std::printf("SKIPPED: %s\n", why);
  std::fflush(stdout);
  std::exit(MBI_SKIP_CODE);
}

/// The folder of the real models ($MBI_MODELS_DIR), or skips the test when it is not set.
inline std::filesystem::path models_dir_or_skip() {
  const char* dir = std::getenv("MBI_MODELS_DIR");
  if (!dir || !*dir) skip("MBI_MODELS_DIR is not set (real models are not committed)");
  return dir;
}

}  // namespace mbi::test
