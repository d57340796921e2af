// libFuzzer target: legacy VTK, ASCII and binary: mesh and deformed points (mbi::io::parse_vtk_mesh, parse_vtk_points) (docs/hardening.md; seeds in tests/fuzz/vtk/).
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view in = mbi::fuzz::bytes(data, size);
  try {
    mbi::fuzz::check_positions(mbi::io::parse_vtk_points(in, "fuzz.vtk"));
    mbi::fuzz::check_control(mbi::io::parse_vtk_mesh(in, "fuzz.vtk"));
  } catch (const mbi::io::Error&) {
  }
  return 0;
}
