#pragma once
#include <stdexcept>

namespace mbi::sim {

/// Every error mbi::sim throws. The message names the element, node, handle or argument.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace mbi::sim
