#pragma once
// The viewer's error (no GL here, so that the script reader builds without it).
#include <mbi/error.hpp>

namespace mbi::viewer {

/// No display, no OpenGL 3.3 window, a bad script or a file the session cannot use: the message
/// says which.
class Error : public mbi::Error {
 public:
  using mbi::Error::Error;
};

}  // namespace mbi::viewer
