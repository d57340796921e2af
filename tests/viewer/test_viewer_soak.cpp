// The viewer over a long session: 10,000 frames of a small scene under Xvfb with scripted pokes,
// method switches and alpha changes; the resident memory the viewer reports (/proc/self/status)
// at frame 10,000 is at most 10 MB above that at frame 100.
#include <catch2/catch.hpp>

// Under AddressSanitizer (the sanitizer pass: -O0) frames are many times slower and freed memory
// waits in ASan's quarantine (up to 256 MB), so resident memory says nothing about leaks there:
// that pass runs a tenth of the session for its reports and leaves the memory bound to the
// release pass.
#if defined(__SANITIZE_ADDRESS__)
#define MBI_SOAK_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MBI_SOAK_UNDER_ASAN 1
#endif
#endif
#ifdef MBI_SOAK_UNDER_ASAN
constexpr int kFrames = 1000;
constexpr bool kCheckMemory = false;
#else
constexpr int kFrames = 10000;
constexpr bool kCheckMemory = true;
#endif

#include "viewer_run.hpp"

#include <cmath>
#include <set>

namespace fs = std::filesystem;
using mbi::test::quoted;

TEST_CASE("mbi view soak: 10,000 frames of pokes, method switches and alpha changes in bounded memory",
          "[viewer][xvfb][soak][long]") {
  mbi::test::TempDir dir("soak");
  {
    // every 100 frames a poke (the right view's middle in a 320 x 240 window, pulled for 30
    // frames); every 300 the next method, every 200 alpha halved or doubled
    std::ofstream s(dir / "soak.txt");
    for (int f = 0; f < kFrames; f += 100) {
      s << f + 10 << " press 240 120 0\n";
      for (int k = 1; k <= 30; ++k) s << f + 10 + k << " move " << 240 + 2 * k << " " << 120 - k << "\n";
      s << f + 41 << " release 300 90 0\n";
      if (f % 300 == 0) s << f + 60 << " key m\n";
      if (f % 200 == 0) s << f + 70 << " key " << (f % 400 == 0 ? "[" : "]") << "\n";
    }
  }
  const fs::path scene = mbi::test::source_dir() / "tests" / "viewer" / "soak.toml";
  const mbi::test::ViewRun r = view(quoted(scene) + " --frames " + std::to_string(kFrames) +
                                        " --no-panel --width 320 --height 240 --script " + quoted(dir / "soak.txt") +
                                        " --report " + quoted(dir / "r.json"),
                                    dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  const nlohmann::json rep = mbi::test::read_report(dir / "r.json");
  REQUIRE(rep.size() == kFrames);
  int poked = 0;
  std::set<std::string> methods;
  std::set<double> alphas;
  for (const auto& fr : rep) {
    REQUIRE(fr["finite"].get<bool>());
    poked += fr.contains("poke");
    methods.insert(fr["method"].get<std::string>());
    alphas.insert(fr["alpha"].get<double>());
  }
  CHECK(poked > kFrames / 10);
  CHECK(methods.size() == 3);
  CHECK(alphas.size() >= 2);
  REQUIRE(rep[100].contains("resident_kb"));
  const long long at100 = rep[100]["resident_kb"], at_end = rep[kFrames - 1]["resident_kb"];
  WARN("resident memory: frame 100 " << at100 << " kB, frame " << kFrames << " " << at_end << " kB (+"
                                     << at_end - at100 << " kB); " << poked << " poked frames");
  if (kCheckMemory) CHECK(at_end - at100 <= 10000);
}
