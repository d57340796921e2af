#include "io_common.hpp"

#include <mbi/io/atomic_file.hpp>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <system_error>

namespace mbi::io::detail {

void fail(const std::filesystem::path& file, int line, const std::string& what) {
  std::string msg = file.string();
  if (line > 0) msg += ":" + std::to_string(line);
  msg += ": " + what;
  throw Error(msg);
}

namespace {
// What a file system object is, for messages: "a directory", "a FIFO (named pipe)", ...
const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}
}  // namespace

void require_regular_file(const std::filesystem::path& file) {
  struct stat st {};
  if (::stat(file.c_str(), &st) != 0) {
    const int err = errno;
    fail(file, 0, std::string("cannot open for reading (") + std::strerror(err) + ")");
  }
  if (!S_ISREG(st.st_mode)) fail(file, 0, std::string("is ") + kind_of(st.st_mode) + ", not a regular file");
}

std::string slurp(const std::filesystem::path& file) {
  // The type is checked before opening (a FIFO would block open() and read() forever, a device
  // such as /dev/zero never ends), and again on the descriptor (the path may have changed).
  require_regular_file(file);
  struct stat st {};
  const int fd = ::open(file.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    fail(file, 0, std::string("cannot open for reading (") + std::strerror(err) + ")");
  }
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  if (::fstat(fd, &st) != 0) fail(file, 0, "cannot determine the file size");
  if (!S_ISREG(st.st_mode)) fail(file, 0, std::string("is ") + kind_of(st.st_mode) + ", not a regular file");
  const auto size = static_cast<std::uintmax_t>(st.st_size);
  if (size > kMaxFileBytes)
    fail(file, 0, "file of " + std::to_string(size) + " bytes is larger than the " +
                      std::to_string(kMaxFileBytes) + " bytes a reader accepts");
  std::string data(static_cast<std::size_t>(size), '\0');
  std::size_t got = 0;
  while (got < data.size()) {
    const ssize_t r = ::read(fd, data.data() + got, data.size() - got);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) {
      const int err = errno;
      fail(file, 0, std::string("read error (") + std::strerror(err) + ")");
    }
    if (r == 0) break;  // shrank while being read: what was there
    got += static_cast<std::size_t>(r);
  }
  data.resize(got);
  return data;
}

std::string_view skip_bom(std::string_view data) {
  if (data.size() >= 3 && static_cast<unsigned char>(data[0]) == 0xEF &&
      static_cast<unsigned char>(data[1]) == 0xBB && static_cast<unsigned char>(data[2]) == 0xBF)
    data.remove_prefix(3);
  return data;
}

int LineCounter::line_of(std::size_t at) {
  at = std::min(at, text_.size());
  if (at < at_) {  // backwards (rare: error messages): count from the start
    at_ = 0;
    line_ = 1;
  }
  // line ends: LF, CR LF (one), lone CR
  for (std::size_t i = at_; i < at; ++i)
    if (text_[i] == '\n' || (text_[i] == '\r' && (i + 1 >= text_.size() || text_[i + 1] != '\n')))
      ++line_;
  at_ = at;
  return static_cast<int>(std::min<long long>(line_, std::numeric_limits<int>::max()));
}

bool LineReader::next(std::string_view& line) {
  if (pos_ >= text_.size()) return false;
  std::size_t end = text_.find_first_of("\r\n", pos_);
  if (end == std::string_view::npos) end = text_.size();
  line = text_.substr(pos_, end - pos_);
  pos_ = end + (end + 1 < text_.size() && text_[end] == '\r' && text_[end + 1] == '\n' ? 2 : 1);
  if (number_ < std::numeric_limits<int>::max()) ++number_;
  return true;
}

std::vector<std::string_view> words(std::string_view s, char comment, std::string_view extra_seps) {
  if (comment != 0) {
    const std::size_t c = s.find(comment);
    if (c != std::string_view::npos) s = s.substr(0, c);
  }
  auto is_sep = [&](char ch) {
    return ch == ' ' || ch == '\t' || ch == '\r' || ch == '\f' || ch == '\v' ||
           extra_seps.find(ch) != std::string_view::npos;
  };
  std::vector<std::string_view> tok;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && is_sep(s[i])) ++i;
    const std::size_t b = i;
    while (i < s.size() && !is_sep(s[i])) ++i;
    if (i > b) tok.push_back(s.substr(b, i - b));
  }
  return tok;
}

std::vector<Line> tokenize(std::string_view text, char comment, std::string_view extra_seps) {
  std::vector<Line> lines;
  LineReader reader(text);
  std::string_view s;
  while (reader.next(s)) {
    Line line{reader.number(), words(s, comment, extra_seps)};
    if (!line.tok.empty()) lines.push_back(std::move(line));
  }
  return lines;
}

namespace {
// std::from_chars for double. A standard library without it (libc++ before 17, the browser
// build's) gets strtod on a copy, held to from_chars' grammar: no leading space, no hex.
std::from_chars_result double_from_chars(const char* b, const char* e, double& x) {
#if defined(__cpp_lib_to_chars)
  return std::from_chars(b, e, x);
#else
  const std::string text(b, e);
  const std::size_t digits = text.find_first_not_of("+-");
  if (text.empty() || std::isspace(static_cast<unsigned char>(text[0])) ||
      (digits != std::string::npos && text.compare(digits, 2, "0x") == 0) ||
      (digits != std::string::npos && text.compare(digits, 2, "0X") == 0))
    return {b, std::errc::invalid_argument};
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str()) return {b, std::errc::invalid_argument};
  const char* ptr = b + (end - text.c_str());
  if (errno == ERANGE) return {ptr, std::errc::result_out_of_range};
  x = v;
  return {ptr, std::errc()};
#endif
}
}  // namespace

double to_double(std::string_view s, const std::filesystem::path& file, int line,
                 const std::string& field) {
  double x = 0.0;
  const char* b = s.data();
  const char* e = s.data() + s.size();
  if (s.size() > 1 && *b == '+' && b[1] != '-' && b[1] != '+') ++b;  // "+1", never "+-1"
  const auto r = double_from_chars(b, e, x);
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
  if (s.size() > 1 && *b == '+' && b[1] != '-' && b[1] != '+') ++b;  // "+1", never "+-1"
  const auto r = std::from_chars(b, e, x);
  if (r.ec != std::errc() || r.ptr != e)
    fail(file, line, field + ": not an integer '" + std::string(s) + "'");
  if (x < lo || x > hi)
    fail(file, line,
         field + ": " + std::to_string(x) + " out of range [" + std::to_string(lo) + ", " +
             std::to_string(hi) + "]");
  return x;
}

double to_coordinate(std::string_view s, const std::filesystem::path& file, int line,
                     const std::string& field) {
  const double x = to_double(s, file, line, field);
  check_coordinate(x, file, line, field);
  return x;
}

void check_coordinate(double x, const std::filesystem::path& file, int line,
                      const std::string& field) {
  if (!std::isfinite(x)) fail(file, line, field + ": non-finite coordinate");
  if (std::abs(x) > kMaxCoordinate)
  {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", x);
    fail(file, line, field + ": " + buf +
                         " is larger in magnitude than 1e300, the largest coordinate accepted");
  }
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
  if (bytes > 0 && std::fwrite(data, 1, bytes, f) != bytes)
    fail(file, 0, std::string("write error (") + (errno != 0 ? std::strerror(errno) : "an I/O error") + ")");
}

void put(std::FILE* f, const std::string& s, const std::filesystem::path& file) {
  put(f, s.data(), s.size(), file);
}

void put_buffered(std::string& out, std::FILE* f, const std::filesystem::path& file) {
  if (out.size() >= (1u << 20)) {
    put(f, out.data(), out.size(), file);
    out.clear();
  }
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

namespace mbi::io {

std::string lower_extension(const std::filesystem::path& file) {
  std::string e = file.extension().string();
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}
std::string read_bytes(const std::filesystem::path& file) { return detail::slurp(file); }
}  // namespace mbi::io
