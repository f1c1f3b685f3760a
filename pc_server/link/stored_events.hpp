#pragma once
// The server's side of store-and-forward (docs/store-and-forward.md): which
// stored Events and Acks of each robot were filed, so that one resent after
// a reconnect or a robot restart is filed once. Per robot it keeps the event
// stream of its journal (Hello.event_stream) and the highest sequence number
// filed; a robot sends its stream in order, so "filed" is "seq <= highest".
// A new stream (the robot lost its journal, or a new robot) starts afresh.
// Thread-safe (sessions of different robots may run on different threads).
#include <cstdint>
#include <map>
#include <mutex>
#include <string>

namespace inspect::server {

class StoredEvents {
 public:
  /// Whether (stream, seq) of `robot` is new: then it is taken as filed.
  bool fileOnce(const std::string& robot, uint64_t stream, uint64_t seq) {
    std::lock_guard lk(mu_);
    auto& s = robots_[robot];
    if (s.stream != stream) s = {stream, 0, s.duplicates};
    if (seq <= s.highest) {
      ++s.duplicates;
      return false;
    }
    s.highest = seq;
    return true;
  }
  /// The highest sequence number of `stream` filed for `robot` (0 = none):
  /// what Envelope.delivered confirms.
  uint64_t highest(const std::string& robot, uint64_t stream) const {
    std::lock_guard lk(mu_);
    const auto it = robots_.find(robot);
    return it != robots_.end() && it->second.stream == stream ? it->second.highest : 0;
  }
  /// Resent entries that were already filed (not filed again).
  uint64_t duplicates(const std::string& robot) const {
    std::lock_guard lk(mu_);
    const auto it = robots_.find(robot);
    return it == robots_.end() ? 0 : it->second.duplicates;
  }

 private:
  struct State {
    uint64_t stream = 0;
    uint64_t highest = 0;
    uint64_t duplicates = 0;
  };
  mutable std::mutex mu_;
  std::map<std::string, State> robots_;
};

}  // namespace inspect::server
