#pragma once
// The interaction library's error.
#include <mbi/error.hpp>

namespace mbi::interact {

/// A malformed ray (zero or non-finite direction), a mesh of the wrong shape or without
/// triangles, a negative reach: the message names the function and the argument.
class Error : public mbi::Error {
 public:
  using mbi::Error::Error;
};

}  // namespace mbi::interact
