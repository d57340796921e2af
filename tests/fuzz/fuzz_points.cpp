// libFuzzer target: point lists and deformed positions (.txt/.xyz, mbi::io::parse_points) (docs/hardening.md; seeds in tests/fuzz/points/).
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view in = mbi::fuzz::bytes(data, size);
  try {
    const Eigen::MatrixXd P = mbi::io::parse_points(in, "fuzz.txt");
    mbi::fuzz::check_positions(P);
  } catch (const mbi::io::Error&) {
  }
  return 0;
}
