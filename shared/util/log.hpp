#pragma once
// The one logger: timestamped lines on stderr, tagged by component.
// High-rate data belongs in telemetry, never in log lines.
#include <sstream>
#include <string_view>

namespace inspect::log {

enum class Level { kDebug = 0, kInfo = 1, kWarn = 2, kError = 3 };

/// Minimum level written (default kInfo; INSPECT_LOG=debug|info|warn|error overrides).
void setLevel(Level l);
Level level();
/// Writes one line; thread-safe.
void write(Level l, std::string_view tag, std::string_view text);

template <class... A>
void logf(Level l, std::string_view tag, const A&... a) {
  if (l < level()) return;
  std::ostringstream os;
  (os << ... << a);
  write(l, tag, os.str());
}
/// The tags of the components that log from several files.
namespace tag {
inline constexpr std::string_view kLink = "link";
inline constexpr std::string_view kOperator = "operator";
inline constexpr std::string_view kRecord = "record";
inline constexpr std::string_view kServer = "pc_server";
inline constexpr std::string_view kVideo = "video";
}  // namespace tag

template <class... A> void debug(std::string_view tag, const A&... a) { logf(Level::kDebug, tag, a...); }
template <class... A> void info(std::string_view tag, const A&... a) { logf(Level::kInfo, tag, a...); }
template <class... A> void warn(std::string_view tag, const A&... a) { logf(Level::kWarn, tag, a...); }
template <class... A> void error(std::string_view tag, const A&... a) { logf(Level::kError, tag, a...); }

}  // namespace inspect::log
