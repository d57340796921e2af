// libFuzzer target: Gmsh .msh 2.2/4.0/4.1, ASCII and binary: mesh and deformed nodes (mbi::io::parse_gmsh, parse_gmsh_nodes) (docs/hardening.md; seeds in tests/fuzz/gmsh/).
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view in = mbi::fuzz::bytes(data, size);
  try {
    mbi::fuzz::check_positions(mbi::io::parse_gmsh_nodes(in, "fuzz.msh"));
    mbi::fuzz::check_control(mbi::io::parse_gmsh(in, "fuzz.msh"));
  } catch (const mbi::io::Error&) {
  }
  return 0;
}
