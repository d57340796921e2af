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
  const mbi::interp::MemoryEstimate e = check_run_size("s", 250000, box.U, box.T, 64.0 * 1024 * 1024 * 1024);
  CHECK(e.peak_bytes > e.factor_bytes);
  CHECK_THROWS_WITH(check_run_size("s", 250000, box.U, box.T, 1024.0 * 1024),
                    Catch::StartsWith("s: the modified-BI precompute would need about") &&
                        Catch::Contains("of --max-memory") && Catch::Contains("30492 unknowns"));
  // the simulator's blocks count when the scene simulates
  const double limit = e.peak_bytes * 1.001;
  CHECK_NOTHROW(check_run_size("s", 250000, box.U, box.T, limit));
  CHECK_THROWS(check_run_size("s", 250000, box.U, box.T, limit, {}, true));
  std::string name;
  CHECK(memory_limit(5e9, name) == 5e9);
  CHECK(name == "--max-memory");
  CHECK(memory_limit(0, name) > 0);
  CHECK(name != "--max-memory");
  // the floor grows with every size and counts in 64 bits
  CHECK(minimum_run_bytes(2000000, 450, 2000, 3) > minimum_run_bytes(1000000, 450, 2000, 3));
  CHECK(minimum_run_bytes(1000, 20000, 120000, 3) > minimum_run_bytes(1000, 10000, 60000, 3));
  CHECK(minimum_run_bytes(3000000000LL, 10, 10, 3) > 3e9 * 8);
  CHECK(over_memory_floor(1000, 1000, 5000, 3).empty());
  CHECK_THAT(over_memory_floor(1000000000000LL, 450, 2000, 3), Catch::Contains("needs at least"));
}

// A container's memory limit (cgroup) counts like a smaller machine.
TEST_CASE("run size: the control group's memory limit, cgroup v1 and v2", "[limits]") {
  mbi::test::TempDir dir("cgroup");
  const std::filesystem::path root = dir.path();
  auto put = [&](const std::filesystem::path& rel, const std::string& text) {
    std::filesystem::create_directories((root / rel).parent_path());
    std::ofstream(root / rel) << text;
  };
  // nothing mounted: no limit
  CHECK(cgroup_memory_limit("0::/user.slice\n", root) == 0.0);
  // v2: the smallest memory.max on the path up to the mount; "max" is no limit
  put("a/b/memory.max", "max\n");
  put("a/memory.max", "2147483648\n");
  put("memory.max", "8589934592\n");
  CHECK(cgroup_memory_limit("0::/a/b\n", root) == 2147483648.0);
  CHECK(cgroup_memory_limit("0::/\n", root) == 8589934592.0);
  // v1 (memory controller among others); about 2^63 means unlimited
  put("memory/docker/x/memory.limit_in_bytes", "9223372036854771712\n");
  put("memory/memory.limit_in_bytes", "1073741824\n");
  CHECK(cgroup_memory_limit("12:cpu,cpuacct:/docker/x\n4:memory:/docker/x\n", root) == 1073741824.0);
  // hybrid: v2 under unified/ beside v1; the smaller wins
  put("unified/s/memory.max", "536870912\n");
  CHECK(cgroup_memory_limit("4:memory:/docker/x\n0::/s\n", root) == 536870912.0);
  // malformed lines and files are no limit, not an error
  put("memory/bad/memory.limit_in_bytes", "lots\n");
  CHECK(cgroup_memory_limit("garbage\n4:memory\n4:memory:relative\n4:memory:/../etc\n", root) == 0.0);
  CHECK(cgroup_memory_limit("4:memory:/bad\n", root) == 1073741824.0);  // the parent's limit
  // this process: positive, and never more than the machine
  const double usable = usable_memory_bytes();
  CHECK(usable > 0);
  CHECK(usable <= physical_memory_bytes());
}
