// libFuzzer target: MDD point caches (mbi::io::parse_mdd) (docs/hardening.md; seeds in tests/fuzz/mdd/).
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view in = mbi::fuzz::bytes(data, size);
  try {
    const mbi::io::PointCache pc = mbi::io::parse_mdd(in, "fuzz.mdd");
    mbi::fuzz::invariant(pc.times.size() == pc.frames.size(), "MDD times and frames differ in count");
    for (const auto& f : pc.frames) {
      mbi::fuzz::invariant(f.cols() == 3, "MDD frame not n x 3");
      mbi::fuzz::check_positions(f);
    }
  } catch (const mbi::io::Error&) {
  }
  return 0;
}
