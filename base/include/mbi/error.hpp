#pragma once
// The one error type of mbi. Every library's error derives from mbi::Error (mbi::interp::Error,
// mbi::sim::Error, mbi::io::IoError, mbi::generate::CageError, mbi::scenes::SceneError,
// mbi::pipeline errors), so a caller that wants any mbi failure catches this one type. Messages
// name what is at fault (file and line, element, vertex, key or argument).
#include <stdexcept>

namespace mbi {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace mbi
