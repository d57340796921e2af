#pragma once
// The ball that the contact tests drop (a file written once per process) and a scene text run as
// `mbi run` runs it (tests/scenes/).
#include <catch2/catch.hpp>

#include <mbi/scenes/runner.hpp>

#include "common/temp_dir.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

namespace mbi::test {

// A ball of radius 0.5 about the origin (a latitude-longitude sphere, 482 vertices), written once
// per process: small enough for the sanitizer build.
inline std::string ball_file() {
  static const mbi::test::TempDir dir("contact-ball");
  static const std::string file = [] {
    const std::filesystem::path path = dir / "ball.obj";
    std::ofstream out(path);
    out.precision(17);
    const int lat = 16, lon = 32;
    const double pi = 3.14159265358979323846;
    out << "v 0 -0.5 0\n";
    for (int i = 1; i < lat; ++i)
      for (int j = 0; j < lon; ++j) {
        const double t = pi * i / lat, f = 2 * pi * j / lon;
        out << "v " << 0.5 * std::sin(t) * std::cos(f) << " " << -0.5 * std::cos(t) << " " << 0.5 * std::sin(t) * std::sin(f)
            << "\n";
      }
    out << "v 0 0.5 0\n";
    auto ring = [&](int i, int j) { return 2 + (i - 1) * lon + j % lon; };  // 1-based
    const int top = 2 + (lat - 1) * lon;
    for (int j = 0; j < lon; ++j) out << "f 1 " << ring(1, j + 1) << " " << ring(1, j) << "\n";
    for (int i = 1; i + 1 < lat; ++i)
      for (int j = 0; j < lon; ++j)
        out << "f " << ring(i, j) << " " << ring(i, j + 1) << " " << ring(i + 1, j + 1) << "\nf " << ring(i, j) << " "
            << ring(i + 1, j + 1) << " " << ring(i + 1, j) << "\n";
    for (int j = 0; j < lon; ++j) out << "f " << top << " " << ring(lat - 1, j) << " " << ring(lat - 1, j + 1) << "\n";
    return path.string();
  }();
  return file;
}

/// Writes `text` as dir/name.toml and runs it as `mbi run` does; the output folder (dir/name).
inline std::filesystem::path run_scene_text(const std::string& text, const TempDir& dir, const std::string& name) {
  const std::filesystem::path file = dir / (name + ".toml");
  std::ofstream(file) << text;
  mbi::scenes::RunOptions o;
  o.out_dir = dir / name;
  const mbi::scenes::RunResult r = mbi::scenes::run_scene(mbi::scenes::load_scene(file), o);
  REQUIRE_FALSE(r.failed);
  return o.out_dir;
}

}  // namespace mbi::test
