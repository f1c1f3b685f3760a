#pragma once
// Start-up failures that are not configuration mistakes (cannot listen, cannot write the port file).
#include <stdexcept>

namespace inspect::util {

/// main() prints what() on one line and exits with status 3.
class StartupError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace inspect::util
