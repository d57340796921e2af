// libFuzzer target: VTK XML .vtu, every encoding: mesh and deformed points (mbi::io::parse_vtu_mesh, parse_vtu_points) (docs/hardening.md; seeds in tests/fuzz/vtu/).
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view in = mbi::fuzz::bytes(data, size);
  try {
    mbi::fuzz::check_positions(mbi::io::parse_vtu_points(in, "fuzz.vtu"));
    mbi::fuzz::check_control(mbi::io::parse_vtu_mesh(in, "fuzz.vtu"));
  } catch (const mbi::io::Error&) {
  }
  return 0;
}
