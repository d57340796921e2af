// libFuzzer target: PC2 point caches (mbi::io::parse_pc2) (docs/hardening.md; seeds in tests/fuzz/pc2/).
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view in = mbi::fuzz::bytes(data, size);
  try {
    const mbi::io::PointCache pc = mbi::io::parse_pc2(in, "fuzz.pc2");
    for (const auto& f : pc.frames) mbi::fuzz::invariant(f.cols() == 3, "PC2 frame not n x 3");
  } catch (const mbi::io::Error&) {
  }
  return 0;
}
