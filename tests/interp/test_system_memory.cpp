// The memory a process may take (mbi/interp/system_memory.hpp): control-group limits, v1 and v2,
// read from a fake mount; the caller's limit against the defaults.
#include <mbi/interp/system_memory.hpp>

#include <catch2/catch.hpp>

#include "common/temp_dir.hpp"

#include <filesystem>
#include <fstream>
#include <string>

using namespace mbi::interp;

// A container's memory limit (cgroup) counts like a smaller machine.
TEST_CASE("system memory: the control group's memory limit, cgroup v1 and v2", "[limits]") {
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

TEST_CASE("system memory: a caller's limit wins, else the smaller of MemAvailable and the usable", "[memory]") {
  std::string name;
  CHECK(memory_limit(5e9, name) == 5e9);
  CHECK(name == "--max-memory");
#ifdef __linux__
  CHECK(memory_limit(0, name) > 0);
  CHECK(name != "--max-memory");
  CHECK(memory_limit(0, name) <= usable_memory_bytes());
#endif
}
