#pragma once
// What the decision core wants announced to the server, and the buffer the
// parts of the core append to between two takes.
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "inspect_robot/v1/link.pb.h"

namespace inspect::robot {

/// One announcement: becomes a v1::Event.
struct CoreEvent {
  v1::Event::Kind kind = v1::Event::INFO;
  std::string text;
  std::optional<v1::GasAlarm> gas_alarm;  // ALARM_RAISED / ALARM_CLEARED
  std::optional<v1::Gains> gains;         // GAINS_APPLIED (with gains_version)
  uint32_t gains_version = 0;
};

/// The events raised since the last take. Appending is the only thing the
/// tick does with it: an event is rare (a mode change, a fault, an alarm),
/// and a tick that raises none allocates nothing.
class EventLog {
 public:
  EventLog() { events_.reserve(16); }
  void push(v1::Event::Kind kind, std::string text) { events_.push_back({kind, std::move(text), {}, {}, 0}); }
  void push(CoreEvent e) { events_.push_back(std::move(e)); }
  /// Swaps the events into `out` (cleared first): the two buffers keep their
  /// capacity, so a caller that keeps `out` allocates nothing once both grew.
  void takeInto(std::vector<CoreEvent>& out) {
    out.clear();
    out.swap(events_);
  }
  bool empty() const { return events_.empty(); }

 private:
  std::vector<CoreEvent> events_;
};

/// The Ack of command `id` with `status` and, for a rejection or a failure, why.
inline v1::Ack ackOf(uint64_t id, v1::Ack::Status status, const std::string& reason = "") {
  v1::Ack a;
  a.set_command_id(id);
  a.set_status(status);
  if (!reason.empty()) a.set_reason(reason);
  return a;
}

/// How a run (a path, a route, a wheel test) ended in a tick: the Ack that
/// answers its command at last, and why the robot went back to IDLE.
struct RunEnd {
  v1::Ack ack;
  std::string why;
};

}  // namespace inspect::robot
