#include "shared/catalog/time_text.hpp"

#include <chrono>
#include <cstdio>
#include <string_view>

namespace inspect::catalog {
namespace {

// Reads exactly n digits from the front of s.
bool takeDigits(std::string_view& s, std::size_t n, int& out) {
  if (s.size() < n) return false;
  out = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (s[i] < '0' || s[i] > '9') return false;
    out = out * 10 + (s[i] - '0');
  }
  s.remove_prefix(n);
  return true;
}

bool skipChar(std::string_view& s, std::string_view any_of) {
  if (s.empty() || any_of.find(s.front()) == std::string_view::npos) return false;
  s.remove_prefix(1);
  return true;
}

}  // namespace

double unixSeconds(Time t) { return std::chrono::duration<double>(t.time_since_epoch()).count(); }

Time fromUnix(double s) {
  return Time(std::chrono::round<std::chrono::microseconds>(std::chrono::duration<double>(s)));
}

std::tm utcParts(Time t) {
  const std::time_t secs = std::chrono::system_clock::to_time_t(std::chrono::floor<std::chrono::seconds>(t));
  std::tm tm{};
  gmtime_r(&secs, &tm);
  return tm;
}

std::string strftimeUtc(Time t, const char* fmt) {
  const std::tm tm = utcParts(t);
  char buf[64];
  return std::string(buf, std::strftime(buf, sizeof buf, fmt, &tm));
}

std::string formatIsoUtc(Time t) {
  const auto ms = std::chrono::floor<std::chrono::milliseconds>(t).time_since_epoch().count() % 1000;
  char frac[8];
  std::snprintf(frac, sizeof frac, ".%03d", static_cast<int>(ms < 0 ? ms + 1000 : ms));
  return strftimeUtc(t, "%Y-%m-%dT%H:%M:%S") + frac + "Z";
}

std::optional<Time> parseIsoUtc(std::string_view s) {
  std::tm tm{};
  int sec = 0;
  double frac = 0;
  if (!takeDigits(s, 4, tm.tm_year) || !skipChar(s, "-") || !takeDigits(s, 2, tm.tm_mon) || !skipChar(s, "-") ||
      !takeDigits(s, 2, tm.tm_mday))
    return std::nullopt;
  if (skipChar(s, "T ")) {
    if (!takeDigits(s, 2, tm.tm_hour) || !skipChar(s, ":") || !takeDigits(s, 2, tm.tm_min)) return std::nullopt;
    if (skipChar(s, ":")) {
      if (!takeDigits(s, 2, sec)) return std::nullopt;
      if (skipChar(s, ".")) {
        double scale = 0.1;
        int digit = 0, n = 0;
        for (; n < 9 && takeDigits(s, 1, digit); ++n, scale /= 10) frac += digit * scale;
        if (n == 0) return std::nullopt;
      }
    }
    skipChar(s, "Z");
  }
  if (!s.empty() || tm.tm_mon < 1 || tm.tm_mon > 12 || tm.tm_mday < 1 || tm.tm_hour > 23 || tm.tm_min > 59 ||
      sec > 59)
    return std::nullopt;
  const int mday = tm.tm_mday;
  tm.tm_year -= 1900;
  tm.tm_mon -= 1;
  tm.tm_sec = sec;
  const std::time_t secs = timegm(&tm);
  if (tm.tm_mday != mday) return std::nullopt;  // e.g. 02-30, normalized by timegm
  return std::chrono::system_clock::from_time_t(secs) +
         std::chrono::round<std::chrono::microseconds>(std::chrono::duration<double>(frac));
}

}  // namespace inspect::catalog
