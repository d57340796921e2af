// What memory this process may take: the machine's, its control group's limit, MemAvailable
// (see mbi/interp/system_memory.hpp). No Eigen: the scene parser's fuzz target links it alone.
#include <mbi/interp/system_memory.hpp>

#include <unistd.h>

#include <fstream>
#include <sstream>

namespace mbi::interp {

double physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || size <= 0) return 0.0;
  return static_cast<double>(pages) * static_cast<double>(size);
}

namespace {
// The number in a cgroup limit file, 0 for "max", unreadable or unlimited (v1 writes about 2^63).
double limit_in(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string word;
  if (!(in >> word) || word == "max") return 0.0;
  char* end = nullptr;
  const double v = std::strtod(word.c_str(), &end);
  if (end == word.c_str() || *end != '\0' || !(v > 0) || v >= 1152921504606846976.0) return 0.0;  // 2^60
  return v;
}

// The smallest limit in `name` from `dir` up to `top` (both under the mount), 0 when none.
double smallest_up(const std::filesystem::path& top, const std::string& rel, const std::string& name) {
  double best = 0.0;
  std::filesystem::path p = rel;
  for (;;) {
    const double v = limit_in(top / p.relative_path() / name);
    if (v > 0 && (best == 0 || v < best)) best = v;
    if (!p.has_relative_path()) break;
    p = p.parent_path();
  }
  return best;
}
}  // namespace

double cgroup_memory_limit(const std::string& proc_self_cgroup, const std::filesystem::path& root) {
  double best = 0.0;
  auto take = [&](double v) {
    if (v > 0 && (best == 0 || v < best)) best = v;
  };
  std::istringstream lines(proc_self_cgroup);
  std::string line;
  while (std::getline(lines, line)) {
    // hierarchy-ID:controller-list:cgroup-path
    const size_t a = line.find(':'), b = a == std::string::npos ? a : line.find(':', a + 1);
    if (b == std::string::npos) continue;
    const std::string id = line.substr(0, a), controllers = line.substr(a + 1, b - a - 1), path = line.substr(b + 1);
    if (path.empty() || path[0] != '/' || path.find("..") != std::string::npos) continue;
    if (id == "0" && controllers.empty()) {  // v2: the whole mount, or unified/ beside v1
      take(smallest_up(root, path, "memory.max"));
      take(smallest_up(root / "unified", path, "memory.max"));
    } else {
      std::istringstream names(controllers);
      std::string c;
      while (std::getline(names, c, ','))
        if (c == "memory") take(smallest_up(root / "memory", path, "memory.limit_in_bytes"));
    }
  }
  return best;
}

namespace {
// usable_memory_bytes(), and whether the control group's limit is what bounds it
double usable_memory(bool& by_group) {
  const double physical = physical_memory_bytes();
#ifdef __EMSCRIPTEN__  // the page: no file system, no control group; the heap's limit alone
  by_group = false;
  return physical;
#endif
  std::ifstream in("/proc/self/cgroup");
  std::stringstream text;
  text << in.rdbuf();
  const double group = cgroup_memory_limit(text.str(), "/sys/fs/cgroup");
  by_group = group > 0 && (physical <= 0 || group < physical);
  return by_group ? group : physical;
}
}  // namespace

double usable_memory_bytes() {
  bool by_group = false;
  return usable_memory(by_group);
}

double available_memory_bytes() {
#ifdef __EMSCRIPTEN__  // the page has no /proc: its heap's limit is the caller's to check
  return 0.0;
#endif
  std::ifstream in("/proc/meminfo");
  std::string key, unit;
  double value = 0;
  while (in >> key >> value) {
    std::getline(in, unit);
    if (key == "MemAvailable:") return value * 1024.0;  // the file's unit: kB
  }
  return 0.0;
}

double memory_limit(double max_memory, std::string& name) {
  if (max_memory > 0) {
    name = "--max-memory";
    return max_memory;
  }
  bool by_group = false;
  const double usable = usable_memory(by_group), available = available_memory_bytes();
  if (available > 0 && (usable <= 0 || available <= usable)) {
    name = "MemAvailable (/proc/meminfo)";
    return available;
  }
  name = by_group ? "this process's control group limit" : "this machine's memory";
  return usable;
}

}  // namespace mbi::interp
