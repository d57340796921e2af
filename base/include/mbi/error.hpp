#pragma once
// The one error type of mbi. Each library that has an error type of its own names it Error in its
// namespace (mbi::interp::Error, mbi::sim::Error, mbi::io::Error, mbi::generate::Error,
// mbi::scenes::Error, mbi::gpu::Error, mbi::viewer::Error), derived from mbi::Error, so a caller
// that wants any mbi failure catches this one type. Messages name what is at fault (file and
// line, element, vertex, key or argument).
#include <stdexcept>

namespace mbi {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace mbi
