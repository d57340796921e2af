// Point lists (.txt, .xyz): one point per line, d numbers separated by blanks or commas.
#include "io_common.hpp"

namespace mbi::io {

Eigen::MatrixXd read_points(const std::filesystem::path& file) {
  return parse_points(detail::slurp(file), file);
}

Eigen::MatrixXd parse_points(std::string_view data, const std::filesystem::path& file) {
  const auto lines = detail::tokenize(detail::skip_bom(data), '#', ",");
  if (lines.empty()) return Eigen::MatrixXd(0, 0);
  const std::size_t d = lines[0].tok.size();
  // Every line's count first: the matrix is allocated only for as many numbers as there are
  // (a first line of a million numbers followed by short lines must not allocate lines x 1e6).
  for (std::size_t i = 0; i < lines.size(); ++i)
    if (lines[i].tok.size() != d)
      detail::fail(file, lines[i].number, "point " + std::to_string(i) + ": " +
                                              std::to_string(lines[i].tok.size()) +
                                              " numbers, expected " + std::to_string(d) +
                                              " as on the first line");
  Eigen::MatrixXd P(static_cast<Eigen::Index>(lines.size()), static_cast<Eigen::Index>(d));
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const auto& l = lines[i];
    const std::string field = "point " + std::to_string(i);
    for (std::size_t c = 0; c < d; ++c)
      P(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(c)) =
          detail::to_coordinate(l.tok[c], file, l.number, field + " coordinate " + std::to_string(c));
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
