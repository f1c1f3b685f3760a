#pragma once
// Numbers in the tuning host's messages and tables.
#include <iomanip>
#include <sstream>
#include <string>

namespace inspect::tuning {

/// `v` with `digits` significant digits, as an ostream writes it ("0.2", "1.5e-05").
inline std::string significant(double v, int digits) {
  std::ostringstream os;
  os << std::setprecision(digits) << v;
  return os.str();
}

}  // namespace inspect::tuning
