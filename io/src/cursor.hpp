#pragma once
// A reader of the Gmsh and legacy VTK formats' data (format_gmsh.cpp, format_vtk.cpp): words of
// text, or binary values in the file's byte order. Messages name the line (text) or the byte
// offset (binary).
#include "io_common.hpp"

#include <cctype>
#include <cmath>

namespace mbi::io::detail {

struct Cursor {
  std::string_view d;
  const std::filesystem::path& file;
  std::size_t pos = 0;
  std::size_t last = 0;  // where the last word / value began
  bool binary = false, swap = false;
  LineCounter lines{d};

  int line_at(std::size_t at) {
    return binary && at > 0 ? 0 : lines.line_of(at);
  }
  [[noreturn]] void fail_here(const std::string& what) {
    if (binary) fail(file, 0, what + " (byte " + std::to_string(last) + ")");
    fail(file, line_at(last), what);
  }
  bool at_end() {
    while (pos < d.size() && std::isspace(static_cast<unsigned char>(d[pos]))) ++pos;
    return pos >= d.size();
  }
  std::string_view word(const char* what) {
    if (at_end()) {
      last = d.size();
      fail(file, 0, std::string("file truncated: expected ") + what);
    }
    last = pos;
    while (pos < d.size() && !std::isspace(static_cast<unsigned char>(d[pos]))) ++pos;
    return d.substr(last, pos - last);
  }
  // After a section keyword of a binary file: exactly one newline, then binary data.
  void end_of_line() {
    while (pos < d.size() && d[pos] != '\n') ++pos;
    if (pos < d.size()) ++pos;
  }
  template <typename T>
  T get(const std::string& what) {
    last = pos;
    if (d.size() - pos < sizeof(T)) fail(file, 0, what + ": file truncated (byte " + std::to_string(pos) + ")");
    pos += sizeof(T);
    return load_bytes<T>(d.data() + last, swap);
  }
  long long integer(const std::string& what, long long lo, long long hi) {
    const std::string_view w = word(what.c_str());
    return to_int(w, file, line_at(last), what, lo, hi);
  }
  double real(const std::string& what) {
    if (binary) {
      const double x = get<double>(what);
      if (!std::isfinite(x)) fail_here(what + ": non-finite value");
      return x;
    }
    const std::string_view w = word(what.c_str());
    return to_double(w, file, line_at(last), what);
  }
  // An int (binary: int32) / a size (binary: `size_bytes` unsigned) / in ASCII a word.
  long long i32(const std::string& what, long long lo, long long hi) {
    if (!binary) return integer(what, lo, hi);
    const long long x = get<std::int32_t>(what);
    if (x < lo || x > hi) fail_here(what + ": " + std::to_string(x) + " out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return x;
  }
  long long size(const std::string& what, long long lo, long long hi, int size_bytes) {
    if (!binary) return integer(what, lo, hi);
    const unsigned long long x = size_bytes == 8 ? get<std::uint64_t>(what) : get<std::uint32_t>(what);
    if (x > static_cast<unsigned long long>(hi) || static_cast<long long>(x) < lo)
      fail_here(what + ": " + std::to_string(x) + " out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return static_cast<long long>(x);
  }
  // Fails unless `count` items of at least `bytes` each can follow.
  void room(long long count, std::size_t bytes, const std::string& what) {
    const long double need = static_cast<long double>(count) * static_cast<long double>(bytes);
    if (need > static_cast<long double>(d.size() - pos))
      fail_here("header says " + std::to_string(count) + " " + what + " but only " + std::to_string(d.size() - pos) + " bytes follow");
  }
  void expect(const char* keyword, const char* hint) {
    const std::string_view w = word(keyword);
    if (w != keyword) fail_here(std::string("expected ") + keyword + ", found '" + std::string(w.substr(0, 40)) + "'" + hint);
  }
};

}  // namespace mbi::io::detail
