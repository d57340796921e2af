// libFuzzer target: ParaView collections (mbi::io::parse_pvd) (docs/hardening.md; seeds in tests/fuzz/pvd/).
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view in = mbi::fuzz::bytes(data, size);
  try {
    const std::vector<mbi::io::PvdEntry> e = mbi::io::parse_pvd(in, "dir/fuzz.pvd");
    mbi::fuzz::invariant(!e.empty(), "a collection without datasets");
    for (std::size_t k = 0; k < e.size(); ++k) {
      mbi::fuzz::invariant(std::isfinite(e[k].time), "timestep not finite");
      mbi::fuzz::invariant(k == 0 || e[k - 1].time < e[k].time, "timesteps not increasing");
      mbi::fuzz::invariant(!e[k].file.empty(), "empty file name");
    }
  } catch (const mbi::io::Error&) {
  }
  return 0;
}
