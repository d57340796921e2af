// libFuzzer target: the OFF reader (mbi::io::parse_surface) (docs/hardening.md; seeds in tests/fuzz/off/).
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view in = mbi::fuzz::bytes(data, size);
  try {
    mbi::fuzz::check_surface(mbi::io::parse_surface(in, "fuzz.off"));
  } catch (const mbi::io::Error&) {
  }
  return 0;
}
