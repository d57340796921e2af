#pragma once
// Helpers shared by the readers and writers of every format: error messages, whole-file
// reading, lines and words of a text, numbers, bytes of binary data, checks and atomic writing.
#include <mbi/io/io.hpp>
#include <mbi/io/parse.hpp>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace mbi::io::detail {

/// Throws Error "<file>:<line>: what" (line > 0) or "<file>: what".
[[noreturn]] void fail(const std::filesystem::path& file, int line, const std::string& what);

/// The whole file as bytes. Only regular files are read: a directory, a FIFO, a device
/// (/dev/zero) or a socket is refused before it is opened (and the file is opened with
/// O_NONBLOCK, so a FIFO swapped in between cannot block), as is a file larger than
/// kMaxFileBytes. Throws Error naming the file and what it is.
std::string slurp(const std::filesystem::path& file);
/// Throws Error unless `file` is a regular file (naming what it is: a directory, a FIFO, ...).
void require_regular_file(const std::filesystem::path& file);

/// `data` without a leading UTF-8 byte-order mark (EF BB BF), if it has one.
std::string_view skip_bom(std::string_view data);

/// Parses a coordinate: a finite double of magnitude at most kMaxCoordinate; otherwise throws
/// "<file>:<line>: <field>: ...".
double to_coordinate(std::string_view s, const std::filesystem::path& file, int line,
                     const std::string& field);
/// Checks a coordinate read from binary data (finite, magnitude at most kMaxCoordinate).
void check_coordinate(double x, const std::filesystem::path& file, int line,
                      const std::string& field);

/// Counts the newlines of a text incrementally: line_of(at) is the 1-based line of byte `at`,
/// in amortised O(distance from the previous query), so that naming lines while parsing a
/// large file does not cost O(size) per number.
class LineCounter {
 public:
  explicit LineCounter(std::string_view text) : text_(text) {}
  int line_of(std::size_t at);

 private:
  std::string_view text_;
  std::size_t at_ = 0;
  long long line_ = 1;
};

/// Reads a text a line at a time. A line ends at LF, CR LF or a lone CR (old Mac files); the
/// last one may have no end.
class LineReader {
 public:
  explicit LineReader(std::string_view text) : text_(text) {}
  /// The next line, without its end, in `line`; false after the last one.
  bool next(std::string_view& line);
  /// The 1-based number of the line `next` gave last (saturates: files of > 2^31 lines).
  int number() const { return number_; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  int number_ = 0;
};

/// The blank-separated words of one line (separators: blanks, tabs, CR, and `extra_seps`),
/// without everything from `comment` on (comment = 0: none). The views point into `line`.
std::vector<std::string_view> words(std::string_view line, char comment = '#',
                                    std::string_view extra_seps = {});

struct Line {
  int number = 0;                      ///< 1-based line number in the file
  std::vector<std::string_view> tok;   ///< blank-separated tokens
};

/// The lines of `text` that have words (see words()), with their numbers. The views point into
/// `text`.
std::vector<Line> tokenize(std::string_view text, char comment = '#',
                           std::string_view extra_seps = {});

/// Parses a finite double; otherwise throws "<file>:<line>: <field>: ...".
double to_double(std::string_view s, const std::filesystem::path& file, int line,
                 const std::string& field);
/// Parses a whole integer token in [lo, hi].
long long to_int(std::string_view s, const std::filesystem::path& file, int line,
                 const std::string& field, long long lo, long long hi);

/// "%.17g".
std::string fmt(double x);

/// Runs `body` on an AtomicFile for `target` and commits it (see atomic_file.hpp).
void write_atomic(const std::filesystem::path& target,
                  const std::function<void(std::FILE*)>& body);

/// fwrite / fputs that throw Error on failure.
void put(std::FILE* f, const void* data, std::size_t bytes, const std::filesystem::path& file);
void put(std::FILE* f, const std::string& s, const std::filesystem::path& file);

/// Checks P finite; throws "<file>: <what> <row>: non-finite coordinate".
void check_finite(const Eigen::Ref<const Eigen::MatrixXd>& P, const std::filesystem::path& file,
                  const char* what);
/// Checks every entry of E in [0, n); throws naming row and column.
void check_indices(const Eigen::Ref<const Eigen::MatrixXi>& E, long long n,
                   const std::filesystem::path& file, const char* what);

/// The T whose sizeof(T) bytes start at p, reversed first when `swap` (the caller checks that
/// they are there).
template <typename T>
T load_bytes(const char* p, bool swap) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if (swap) std::reverse(b, b + sizeof(T));
  T x;
  std::memcpy(&x, b, sizeof(T));
  return x;
}
/// The same, stored little endian.
template <typename T>
T load_le(const char* p) {
  return load_bytes<T>(p, std::endian::native == std::endian::big);
}
/// Appends the bytes of x to `out`, big or little endian.
template <typename T>
void append_bytes(std::string& out, T x, bool big) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &x, sizeof(T));
  if (big != (std::endian::native == std::endian::big)) std::reverse(b, b + sizeof(T));
  out.append(reinterpret_cast<const char*>(b), sizeof(T));
}
/// Writes `out` to f and empties it once it holds 1 MiB (binary writers fill it record by
/// record; the caller writes the rest).
void put_buffered(std::string& out, std::FILE* f, const std::filesystem::path& file);

}  // namespace mbi::io::detail
