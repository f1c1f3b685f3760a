#include "shared/util/number_text.hpp"

#include <charconv>
#include <cstdio>
#include <iomanip>
#include <sstream>

namespace inspect::util {

std::string fmtFixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  std::string s = buf;
  if (s.find_first_not_of("-0.") == std::string::npos && s[0] == '-') s.erase(0, 1);  // no "-0.00"
  return s;
}

std::string fmtSigned(double v, int decimals) {
  std::string s = fmtFixed(v, decimals);
  return s[0] == '-' ? s : "+" + s;
}

std::string fmtShort(double v, int decimals) {
  std::string s = fmtFixed(v, decimals);
  if (s.find('.') != std::string::npos) {
    while (!s.empty() && s.back() == '0') s.pop_back();
    if (!s.empty() && s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

std::string significant(double v, int digits) {
  std::ostringstream os;
  os << std::setprecision(digits) << v;
  return os.str();
}

std::string shortest(double v) {
  char buf[64];
  const auto [p, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return ec == std::errc() ? std::string(buf, p) : "nan";
}

std::string fmtPoint(double x_m, double y_m) { return "(" + fmtFixed(x_m) + ", " + fmtFixed(y_m) + ")"; }

std::string padRight(std::string s, std::size_t width) {
  if (s.size() < width) s.append(width - s.size(), ' ');
  return s;
}

std::string padLeft(std::string s, std::size_t width) {
  if (s.size() < width) s.insert(0, width - s.size(), ' ');
  return s;
}

}  // namespace inspect::util
