#pragma once
#include <mbi/error.hpp>

namespace mbi::sim {

/// Every error mbi::sim throws. The message names the element, node, handle or argument.
class Error : public mbi::Error {
 public:
  using mbi::Error::Error;
};

}  // namespace mbi::sim
