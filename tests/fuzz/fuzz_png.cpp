// libFuzzer target: PNG input (mbi::io::parse_png; stb_image compiled into the fuzz build) (docs/hardening.md; seeds in tests/fuzz/png/).
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view in = mbi::fuzz::bytes(data, size);
  try {
    const mbi::io::Image img = mbi::io::parse_png(in, "fuzz.png");
    mbi::fuzz::invariant(img.width > 0 && img.height > 0 && img.width <= mbi::io::kMaxImageSide &&
                             img.height <= mbi::io::kMaxImageSide,
                         "image size");
    mbi::fuzz::invariant(img.rgb.size() == static_cast<std::size_t>(img.width) * img.height * 3,
                         "image buffer size");
  } catch (const mbi::io::Error&) {
  }
  return 0;
}
