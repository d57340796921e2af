#pragma once
// Internal helpers of the IO code: error messages, whole-file reading, line tokenising, number
// parsing and atomic writing.
#include <mbi/io/io.hpp>
#include <mbi/io/parse.hpp>

#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace mbi::io::detail {

/// Throws IoError "<file>:<line>: what" (line > 0) or "<file>: what".
[[noreturn]] void fail(const std::filesystem::path& file, int line, const std::string& what);

/// The whole file as bytes. Only regular files are read: a directory, a FIFO, a device
/// (/dev/zero) or a socket is refused before it is opened (and the file is opened with
/// O_NONBLOCK, so a FIFO swapped in between cannot block), as is a file larger than
/// kMaxFileBytes. Throws IoError naming the file and what it is.
std::string slurp(const std::filesystem::path& file);
/// Throws IoError unless `file` is a regular file (naming what it is: a directory, a FIFO, ...).
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

struct Line {
  int number = 0;                      ///< 1-based line number in the file
  std::vector<std::string_view> tok;   ///< blank-separated tokens
};

/// Splits `text` into lines of tokens (separators: blanks, tabs, CR, and `extra_seps`); drops
/// everything from `comment` to the end of a line (comment = 0: none) and lines without tokens.
/// The views point into `text`.
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

/// write_surface with the faces and attributes of `mesh`, and the positions V (n x 3) and
/// normals N (n x 3 or empty) in place of mesh.V and mesh.N (no copy of the mesh per frame).
void write_surface_positions(const std::filesystem::path& file, const SurfaceMesh& mesh,
                             const Eigen::Ref<const Eigen::MatrixXd>& V,
                             const Eigen::Ref<const Eigen::MatrixXd>& N, Encoding encoding);

/// fwrite / fputs that throw IoError on failure.
void put(std::FILE* f, const void* data, std::size_t bytes, const std::filesystem::path& file);
void put(std::FILE* f, const std::string& s, const std::filesystem::path& file);

/// Lower-case extension with the dot ("" if none).
std::string extension(const std::filesystem::path& file);

/// Checks P finite; throws "<file>: <what> <row>: non-finite coordinate".
void check_finite(const Eigen::Ref<const Eigen::MatrixXd>& P, const std::filesystem::path& file,
                  const char* what);
/// Checks every entry of E in [0, n); throws naming row and column.
void check_indices(const Eigen::Ref<const Eigen::MatrixXi>& E, long long n,
                   const std::filesystem::path& file, const char* what);

}  // namespace mbi::io::detail
