#pragma once
// What the server knows about each robot: connection, latest telemetry and its
// rate, events, acks. Written by the network threads, read by the console;
// every member function is thread-safe (one mutex, never held across I/O).
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "pc_server/link/wake_signal.hpp"
#include "inspect_robot/v1/link.pb.h"

namespace inspect::server {

/// A copy of one robot's state at one instant.
struct RobotSnapshot {
  std::string id;
  bool connected = false;
  std::string address;           // "ip:port" of the current or last connection
  std::string software_version;  // from Hello
  std::vector<std::string> capabilities;
  bool has_telemetry = false;
  v1::Telemetry telemetry;       // latest received (kept after a disconnect)
  double telemetry_age_s = -1;   // since the latest telemetry was received; < 0 = none yet
  double telemetry_hz = 0;       // telemetry messages received per second (last second)
  uint64_t telemetry_count = 0;  // over the server's lifetime
  double state_age_s = 0;        // since the robot connected / disconnected
  std::string close_reason;      // why the last connection ended
  v1::Hello hello;               // the last Hello (gas channels, capabilities)
  // Tracking gains: those in force (from Hello, then GAINS_APPLIED events)
  // and the sets the robot had in force before, oldest first (for `gains revert`).
  bool gains_known = false;
  v1::Gains gains;
  uint32_t gains_version = 0;
  std::vector<std::pair<uint32_t, v1::Gains>> gains_history;
};

/// A gas alarm or gas sensor fault as the operator sees it (docs/gas.md):
/// numbered by the server (#1, #2 ...), raised/cleared by the robot,
/// acknowledged by the operator.
struct AlarmRecord {
  int number = 0;
  std::string robot_id;
  v1::GasAlarm alarm;          // the latest transition (active = still raised)
  int64_t raised_ns = 0;       // server monotonic time the raise arrived
  int64_t cleared_ns = 0;      // 0 = still active
  bool acked = false;
  int64_t acked_ns = 0;
  bool active() const { return cleared_ns == 0; }
};

/// One robot event waiting to be shown on the console.
struct PendingEvent {
  std::string robot_id;
  v1::Event event;
};

/// Map robot id -> state. Updates carry the session serial so that a replaced
/// (older) connection cannot overwrite the state of its replacement.
class RobotRegistry {
 public:
  static constexpr std::size_t kMaxAcksPerRobot = 256;
  static constexpr std::size_t kMaxEventsPerRobot = 100;
  static constexpr std::size_t kMaxPendingEvents = 1000;
  static constexpr std::size_t kMaxGainsHistory = 32;
  static constexpr int64_t kRateWindowNs = 1'000'000'000;

  void onConnected(const std::string& id, const std::string& address, uint64_t serial, const v1::Hello& hello,
                   int64_t now_ns);
  void onDisconnected(const std::string& id, uint64_t serial, const std::string& reason, int64_t now_ns);
  void onTelemetry(const std::string& id, uint64_t serial, const v1::Telemetry& t, int64_t now_ns);
  void onEvent(const std::string& id, uint64_t serial, const v1::Event& e, int64_t now_ns = 0);
  void onAck(const std::string& id, uint64_t serial, const v1::Ack& a);

  /// State of one robot; nullopt if it never connected.
  std::optional<RobotSnapshot> snapshot(const std::string& id, int64_t now_ns) const;
  /// All robots ever connected, sorted by id.
  std::vector<RobotSnapshot> snapshots(int64_t now_ns) const;
  int connectedCount() const;
  /// The connected robot that connected first ("" if none).
  std::string firstConnected() const;
  /// The latest Ack of a command (bounded history per robot).
  std::optional<v1::Ack> ack(const std::string& id, uint64_t command_id) const;
  /// Moves with every Ack recorded (onAck): what a console waiting for one sleeps on.
  WakeSignal& ackSignal() { return ack_signal_; }
  /// Events received since the last call, oldest first (one consumer; the
  /// operator sessions use eventsSince, each with its own cursor).
  std::vector<PendingEvent> takeEvents();
  /// Number of events takeEvents() missed (they left the buffer of kMaxPendingEvents first).
  uint64_t droppedEvents() const;
  /// A cursor at the newest event: a new operator session sees events from now on.
  uint64_t eventCursor() const;
  /// Events after `cursor` (advanced past them), oldest first; `missed` counts
  /// those that left the buffer before this reader came for them.
  std::vector<PendingEvent> eventsSince(uint64_t& cursor, uint64_t* missed = nullptr) const;
  /// The robot's recent events, oldest first.
  std::vector<v1::Event> events(const std::string& id) const;

  /// Gas alarms: active ones, or (all) also the cleared ones kept (newest
  /// kMaxAlarms), oldest first; robot_id "" = every robot.
  std::vector<AlarmRecord> alarms(bool all, const std::string& robot_id = "") const;
  /// Acknowledges alarm #number; the record as acknowledged, or nullopt when there is no such alarm.
  std::optional<AlarmRecord> ackAlarm(int number, int64_t now_ns);
  /// Acknowledges every unacknowledged alarm (active or not); returns them.
  std::vector<AlarmRecord> ackAllAlarms(int64_t now_ns);
  /// Active alarms not yet acknowledged.
  int unackedAlarms(const std::string& robot_id = "") const;
  static constexpr std::size_t kMaxAlarms = 500;

 private:
  struct Entry {
    uint64_t serial = 0;
    bool connected = false;
    uint64_t connect_order = 0;
    std::string address;
    std::string software_version;
    std::vector<std::string> capabilities;
    int64_t state_change_ns = 0;
    std::string close_reason;
    bool has_telemetry = false;
    v1::Telemetry telemetry;
    int64_t telemetry_rx_ns = 0;
    uint64_t telemetry_count = 0;
    std::deque<int64_t> rx_times_ns;
    std::map<uint64_t, v1::Ack> acks;
    std::deque<v1::Event> events;
    v1::Hello hello;
    bool gains_known = false;
    v1::Gains gains;
    uint32_t gains_version = 0;
    std::vector<std::pair<uint32_t, v1::Gains>> gains_history;  // sets in force before, oldest first
    int active_alarms = 0;  // records in alarms_ still active: the 50 Hz resync skips the book when 0
  };
  Entry* current(const std::string& id, uint64_t serial);
  /// A set of gains is in force on the robot now; mu_ held.
  static void noteGainsLocked(Entry& e, const v1::Gains& g, uint32_t version);
  RobotSnapshot makeSnapshot(const std::string& id, const Entry& e, int64_t now_ns) const;

  mutable std::mutex mu_;
  WakeSignal ack_signal_;
  std::map<std::string, Entry> robots_;
  uint64_t connect_counter_ = 0;
  std::deque<PendingEvent> pending_;  // the newest kMaxPendingEvents; pending_[i] has number first_event_ + i
  uint64_t first_event_ = 0;
  uint64_t take_cursor_ = 0;
  void pushEventLocked(const std::string& id, const v1::Event& ev);
  std::vector<PendingEvent> eventsSinceLocked(uint64_t& cursor, uint64_t* missed) const;
  /// Applies a robot's alarm transition (or telemetry resync) to the book; mu_ held.
  void noteAlarmLocked(const std::string& id, const v1::GasAlarm& a, int64_t now_ns);
  std::deque<AlarmRecord> alarms_;
  int alarm_counter_ = 0;
  uint64_t dropped_events_ = 0;
};

}  // namespace inspect::server
