#include "io_common.hpp"

#include <mbi/io/atomic_file.hpp>

#include <unistd.h>

#include <atomic>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <system_error>

namespace mbi::io::detail {

void fail(const std::filesystem::path& file, int line, const std::string& what) {
  std::string msg = file.string();
  if (line > 0) msg += ":" + std::to_string(line);
  msg += ": " + what;
  throw IoError(msg);
}

std::string slurp(const std::filesystem::path& file) {
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) fail(file, 0, "is a directory, not a file");
  std::ifstream in(file, std::ios::binary);
  if (!in) fail(file, 0, "cannot open for reading");
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) fail(file, 0, "cannot determine the file size");
  in.seekg(0, std::ios::beg);
  std::string data(static_cast<std::size_t>(size), '\0');
  if (size > 0 && !in.read(data.data(), size)) fail(file, 0, "read error");
  return data;
}

std::vector<Line> tokenize(std::string_view text, char comment, std::string_view extra_seps) {
  std::vector<Line> lines;
  int number = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    ++number;
    std::string_view s = text.substr(pos, end - pos);
    if (comment != 0) {
      const std::size_t c = s.find(comment);
      if (c != std::string_view::npos) s = s.substr(0, c);
    }
    Line line;
    line.number = number;
    std::size_t i = 0;
    auto is_sep = [&](char ch) {
      return ch == ' ' || ch == '\t' || ch == '\r' || ch == '\f' || ch == '\v' ||
             extra_seps.find(ch) != std::string_view::npos;
    };
    while (i < s.size()) {
      while (i < s.size() && is_sep(s[i])) ++i;
      const std::size_t b = i;
      while (i < s.size() && !is_sep(s[i])) ++i;
      if (i > b) line.tok.push_back(s.substr(b, i - b));
    }
    if (!line.tok.empty()) lines.push_back(std::move(line));
    pos = end + 1;
  }
  return lines;
}

double to_double(std::string_view s, const std::filesystem::path& file, int line,
                 const std::string& field) {
  double x = 0.0;
  const char* b = s.data();
  const char* e = s.data() + s.size();
  if (!s.empty() && *b == '+') ++b;
  const auto r = std::from_chars(b, e, x);
  if (r.ec == std::errc::result_out_of_range)
    fail(file, line, field + ": number out of range '" + std::string(s) + "'");
  if (r.ec != std::errc() || r.ptr != e)
    fail(file, line, field + ": not a number '" + std::string(s) + "'");
  if (!std::isfinite(x)) fail(file, line, field + ": non-finite value '" + std::string(s) + "'");
  return x;
}

long long to_int(std::string_view s, const std::filesystem::path& file, int line,
                 const std::string& field, long long lo, long long hi) {
  long long x = 0;
  const char* b = s.data();
  const char* e = s.data() + s.size();
  if (!s.empty() && *b == '+') ++b;
  const auto r = std::from_chars(b, e, x);
  if (r.ec != std::errc() || r.ptr != e)
    fail(file, line, field + ": not an integer '" + std::string(s) + "'");
  if (x < lo || x > hi)
    fail(file, line,
         field + ": " + std::to_string(x) + " out of range [" + std::to_string(lo) + ", " +
             std::to_string(hi) + "]");
  return x;
}

std::string fmt(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

void write_atomic(const std::filesystem::path& target,
                  const std::function<void(std::FILE*)>& body) {
  write_file_atomic(target, [&](AtomicFile& f) { body(f.stream()); });
}

void put(std::FILE* f, const void* data, std::size_t bytes, const std::filesystem::path& file) {
  if (bytes > 0 && std::fwrite(data, 1, bytes, f) != bytes) fail(file, 0, "write error");
}

void put(std::FILE* f, const std::string& s, const std::filesystem::path& file) {
  put(f, s.data(), s.size(), file);
}

std::string extension(const std::filesystem::path& file) {
  std::string e = file.extension().string();
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

void check_finite(const Eigen::Ref<const Eigen::MatrixXd>& P, const std::filesystem::path& file,
                  const char* what) {
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    for (Eigen::Index j = 0; j < P.cols(); ++j)
      if (!std::isfinite(P(i, j)))
        fail(file, 0, std::string(what) + " " + std::to_string(i) + ": non-finite coordinate");
}

void check_indices(const Eigen::Ref<const Eigen::MatrixXi>& E, long long n,
                   const std::filesystem::path& file, const char* what) {
  for (Eigen::Index i = 0; i < E.rows(); ++i)
    for (Eigen::Index j = 0; j < E.cols(); ++j)
      if (E(i, j) < 0 || E(i, j) >= n)
        fail(file, 0,
             std::string(what) + " " + std::to_string(i) + ": index " + std::to_string(E(i, j)) +
                 " out of range [0, " + std::to_string(n) + ")");
}

}  // namespace mbi::io::detail
