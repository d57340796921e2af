// The memory of scenes and physical ranges: refused at load, quickly, with the estimate and the
// key in the message, only when a run would not fit (no cap on the counts).
#include <mbi/scenes/limits.hpp>
#include <mbi/scenes/scene.hpp>

#include <catch2/catch.hpp>

#include "common/grid_meshes.hpp"
#include "common/temp_dir.hpp"

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace fs = std::filesystem;
using namespace mbi::scenes;

namespace {
fs::path write_scene(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / "mbi_test_limits";
  fs::create_directories(dir);
  const fs::path p = dir / name;
  std::ofstream(p) << text;
  return p;
}

// Options that let the run take `bytes`.
mbi::interp::Options limited(double bytes) {
  mbi::interp::Options o;
  o.max_memory = bytes;
  return o;
}
}  // namespace

TEST_CASE("scenes whose control mesh cannot fit are refused at load within a second, and no cap on the counts", "[limits]") {
  const std::string head = "[dense]\nbuiltin = \"paper-bar\"\n[control]\n";
  // sizes whose floor alone (minimum_run_bytes) is terabytes: refused before anything is built
  const std::vector<std::pair<std::string, std::string>> cases{
      {"builtin = \"box\"\ncells = [1000, 1000, 1000]\n", "1003003001 control vertices and 6000000000 tetrahedra"},
      {"generate_vertices = 1000000000\n", "1000000000 control vertices needs at least"},
  };
  for (const auto& [control, message] : cases) {
    const fs::path p = write_scene("caps.toml", head + control);
    const auto t0 = std::chrono::steady_clock::now();
    CHECK_THROWS_WITH(load_scene(p), Catch::Contains(message) && Catch::Contains("control.") &&
                                         Catch::Contains("GiB of memory, more than the"));
    // a guard against allocating first (minutes, gigabytes); milliseconds in fact, more under ASan
    CHECK(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < 10.0);
  }
  // what the cap of 20,000 vertices and 150,000 tetrahedra refused loads now
  CHECK_NOTHROW(load_scene(write_scene("c.toml", head + "builtin = \"box\"\ncells = [140, 140]\n")));
  CHECK_NOTHROW(load_scene(write_scene("c.toml", head + "builtin = \"grid-2d\"\ncells = [150, 150]\n")));
  CHECK_NOTHROW(load_scene(write_scene("c.toml", head + "builtin = \"box\"\ncells = [30, 30, 30]\n")));
  CHECK_NOTHROW(load_scene(write_scene("c.toml", head + "generate_vertices = 100000\n")));
}

TEST_CASE("scene values outside their physical range name the key", "[limits]") {
  const std::string head = "[dense]\nbuiltin = \"paper-bar\"\n[control]\nbuiltin = \"paper-bar\"\n";
  const std::vector<std::pair<std::string, std::string>> cases{
      {"[material]\nyoung = -1\n", "material.young"},
      {"[material]\nyoung = 1e300\n", "material.young"},
      {"[material]\ndensity = -1000\n", "material.density"},
      {"[material]\ndensity = 0\n", "material.density"},
      {"[material]\npoisson = 0.5\n", "material.poisson"},
      {"[simulation]\ndt = 0\n", "simulation.dt"},
      {"[simulation]\ndt = -0.01\n", "simulation.dt"},
      {"[simulation]\ngravity = [0, -1e300, 0]\n", "simulation.gravity"},
      {"[[pokes]]\npoint = [0, 0, 0]\ntarget = [0, 0, 0]\nstiffness = 1e300\n", "pokes[0].stiffness"},
  };
  for (const auto& [text, key] : cases) {
    INFO(text);
    CHECK_THROWS_WITH(load_scene(write_scene("range.toml", head + text)), Catch::Contains(key));
  }
}

TEST_CASE("run size: the memory estimate against the limit, no cap on the counts", "[limits]") {
  // 21 x 21 x 20 cells: 22 * 22 * 21 = 10164 vertices, 52920 tetrahedra
  const mbi::test::Mesh box = mbi::test::box_tet_mesh(21, 21, 20);
  const mbi::interp::MemoryEstimate e = check_run_size("s", 250000, box.U, box.T, limited(64.0 * 1024 * 1024 * 1024));
  CHECK(e.peak_bytes > e.factor_bytes);
  CHECK_THROWS_WITH(check_run_size("s", 250000, box.U, box.T, limited(1024.0 * 1024)),
                    Catch::StartsWith("s: the modified-BI precompute would need about") &&
                        Catch::Contains("of --max-memory") && Catch::Contains("30492 unknowns"));
  // the simulator's blocks count when the scene simulates
  const double limit = e.peak_bytes * 1.001;
  CHECK_NOTHROW(check_run_size("s", 250000, box.U, box.T, limited(limit)));
  CHECK_THROWS(check_run_size("s", 250000, box.U, box.T, limited(limit), true));
  // the floor grows with every size and counts in 64 bits
  CHECK(minimum_run_bytes(2000000, 450, 2000, 3) > minimum_run_bytes(1000000, 450, 2000, 3));
  CHECK(minimum_run_bytes(1000, 20000, 120000, 3) > minimum_run_bytes(1000, 10000, 60000, 3));
  CHECK(minimum_run_bytes(3000000000LL, 10, 10, 3) > 3e9 * 8);
  CHECK(over_memory_floor(1000, 1000, 5000, 3).empty());
  CHECK_THAT(over_memory_floor(1000000000000LL, 450, 2000, 3), Catch::Contains("needs at least"));
}
