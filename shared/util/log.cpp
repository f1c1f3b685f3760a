#include "shared/util/log.hpp"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>

namespace inspect::log {
namespace {
Level initialLevel() {
  const char* e = std::getenv("INSPECT_LOG");
  if (!e) return Level::kInfo;
  if (!std::strcmp(e, "debug")) return Level::kDebug;
  if (!std::strcmp(e, "warn")) return Level::kWarn;
  if (!std::strcmp(e, "error")) return Level::kError;
  return Level::kInfo;
}
std::atomic<Level> g_level{initialLevel()};
std::mutex g_mu;
const char* name(Level l) {
  switch (l) {
    case Level::kDebug: return "D";
    case Level::kInfo: return "I";
    case Level::kWarn: return "W";
    case Level::kError: return "E";
  }
  return "?";
}
}  // namespace

void setLevel(Level l) { g_level = l; }
Level level() { return g_level; }

void write(Level l, std::string_view tag, std::string_view text) {
  using namespace std::chrono;
  const auto now = system_clock::now();
  const auto t = system_clock::to_time_t(now);
  const auto ms = duration_cast<milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm tm{};
  localtime_r(&t, &tm);
  char ts[32];
  std::strftime(ts, sizeof ts, "%H:%M:%S", &tm);
  std::lock_guard lk(g_mu);
  std::fprintf(stderr, "%s.%03d %s [%.*s] %.*s\n", ts, static_cast<int>(ms), name(l), static_cast<int>(tag.size()),
               tag.data(), static_cast<int>(text.size()), text.data());
}

}  // namespace inspect::log
