#pragma once
// Small file helpers shared by the tests.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace mbi::test {

/// The source tree (CTest passes MBI_SOURCE_DIR).
inline std::filesystem::path source_dir() {
  const char* s = std::getenv("MBI_SOURCE_DIR");
  REQUIRE(s != nullptr);
  return s;
}

/// A file's bytes ("" when it cannot be read).
inline std::string slurp(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// Writes `text` as the whole file, bytes as given.
inline void write_text(const std::filesystem::path& file, const std::string& text) {
  std::ofstream(file, std::ios::binary) << text;
}

/// Files of unfinished writes (.mbi-tmp.*) in `dir`.
inline int temporaries(const std::filesystem::path& dir) {
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().filename().string().rfind(".mbi-tmp.", 0) == 0) ++n;
  return n;
}

}  // namespace mbi::test
