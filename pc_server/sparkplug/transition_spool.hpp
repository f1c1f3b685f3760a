#pragma once
// The alarm transitions the broker has not confirmed yet, kept in a local
// SQLite file as the catalog's writes are (docs/sparkplug.md "Nothing
// lost"): each lands in the file before it is sent and leaves it when the
// broker confirms it (PUBACK), so a broker outage or a pc_server crash or
// restart loses none, and they go out in the order they came. Not
// thread-safe: the edge node's service calls it under its lock.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "inspect_robot/v1/link.pb.h"

namespace inspect::catalog {
class SqlBackend;
}

namespace inspect::server::sparkplug {

struct SpooledTransition {
  int64_t seq = 0;  // the file's order
  std::string device;
  v1::GasAlarm alarm;  // id, channel, channel_name, level, active, value, robot_time_us
  uint64_t time_ms = 0;
  bool late = false;
};

class TransitionSpool {
 public:
  /// Opens (creates) the file; throws catalog::CatalogError naming it.
  explicit TransitionSpool(const std::string& path);
  ~TransitionSpool();
  TransitionSpool(const TransitionSpool&) = delete;
  TransitionSpool& operator=(const TransitionSpool&) = delete;

  /// Keeps a transition; its seq.
  int64_t append(const std::string& device, const v1::GasAlarm& a, uint64_t time_ms, bool late);
  /// The broker has it.
  void remove(int64_t seq);
  /// Every transition kept, oldest first (what an earlier process left).
  std::vector<SpooledTransition> all();
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::unique_ptr<catalog::SqlBackend> db_;
};

}  // namespace inspect::server::sparkplug
