// libFuzzer target: TetGen .node and .ele (mbi::io::parse_node, parse_tetgen). The input is the .node text, a line "#ele", then the .ele text (# starts a comment in both formats) (docs/hardening.md; seeds in tests/fuzz/tetgen/).
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view in = mbi::fuzz::bytes(data, size);
  try {
    const std::size_t cut = in.find("#ele");
    const std::string_view node = in.substr(0, cut);
    const std::string_view ele = cut == std::string_view::npos ? std::string_view() : in.substr(cut + 4);
    const Eigen::MatrixXd X = mbi::io::parse_node(node, "fuzz.node");
    mbi::fuzz::check_positions(X);
    mbi::fuzz::check_control(mbi::io::parse_tetgen(node, ele, "fuzz"));
  } catch (const mbi::io::Error&) {
  }
  return 0;
}
