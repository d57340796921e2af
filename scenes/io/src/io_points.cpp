// Plain point lists (.txt / .xyz).
#include "io_common.hpp"

namespace mbi::io {

Eigen::MatrixXd read_points(const std::filesystem::path& file) {
  const std::string text = detail::slurp(file);
  const auto lines = detail::tokenize(text, '#', ",");
  if (lines.empty()) return Eigen::MatrixXd(0, 0);
  const std::size_t d = lines[0].tok.size();
  Eigen::MatrixXd P(static_cast<Eigen::Index>(lines.size()), static_cast<Eigen::Index>(d));
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const auto& l = lines[i];
    const std::string field = "point " + std::to_string(i);
    if (l.tok.size() != d)
      detail::fail(file, l.number, field + ": " + std::to_string(l.tok.size()) +
                                       " numbers, expected " + std::to_string(d) +
                                       " as on the first line");
    for (std::size_t c = 0; c < d; ++c)
      P(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(c)) =
          detail::to_double(l.tok[c], file, l.number, field + " coordinate " + std::to_string(c));
  }
  return P;
}

void write_points(const std::filesystem::path& file, const Eigen::Ref<const Eigen::MatrixXd>& P) {
  detail::check_finite(P, file, "point");
  detail::write_atomic(file, [&](std::FILE* f) {
    for (Eigen::Index i = 0; i < P.rows(); ++i) {
      std::string s;
      for (Eigen::Index c = 0; c < P.cols(); ++c) s += (c ? " " : "") + detail::fmt(P(i, c));
      detail::put(f, s + "\n", file);
    }
  });
}

}  // namespace mbi::io
