#pragma once
// What the console needs from the link to command robots (LinkServer in the
// program, a fake in tests). Thread-safe; never blocks on the network.
#include <cstdint>
#include <string>

#include "inspect_robot/v1/link.pb.h"

namespace inspect::server {

class CommandSink {
 public:
  virtual ~CommandSink() = default;
  /// Sets the robot's teleop set-point: sends it at once and re-sends it at the
  /// configured rate until cleared. With `lease_s` > 0 it lapses that long
  /// after this call unless set again: a zero set-point goes out (the robot
  /// ramps down) and the re-send stops (operator silence, docs/failsafes.md).
  /// 0: held until cleared. Returns the id of the first Command, 0 if the robot is not connected.
  virtual uint64_t setTeleop(const std::string& robot_id, double v_m_s, double w_rad_s, double lease_s) = 0;
  /// Stops re-sending the set-point (sends nothing).
  virtual void clearTeleop(const std::string& robot_id) = 0;
  /// Renews a leased set-point's lease from now (an operator's keep-alive);
  /// sends nothing, and does nothing without an active leased set-point.
  virtual void renewTeleop(const std::string& robot_id, double lease_s) {
    (void)robot_id;
    (void)lease_s;
  }
  /// Assigns a new id to `cmd` and sends it; Stop and EStop also clear the set-point.
  /// Returns the id, 0 if the robot is not connected.
  virtual uint64_t sendCommand(const std::string& robot_id, v1::Command cmd) = 0;
  /// Called by the console thread whenever it is responsive (every few tens of ms);
  /// re-sent set-points stop when these calls stop (a hung console must not keep a robot driving).
  virtual void consoleAlive() = 0;
};

}  // namespace inspect::server
