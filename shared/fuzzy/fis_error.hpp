#pragma once
// The one error type of the fuzzy engine: a .fis file or a Fis that cannot be
// used. Thrown only at load/build time, never from evaluation.
#include <stdexcept>
#include <string>

namespace inspect::fuzzy {

/// Loading or validation error; what() is one line "file:line: reason"
/// (or "fis 'name': reason" for systems built in code). main() prints it and
/// exits non-zero.
class FisError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace inspect::fuzzy
