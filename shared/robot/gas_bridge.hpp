#pragma once
// The robot's gas alarms on the wire: the alarm monitor (shared/gas) fed
// from the sensor frames on the MCU clock, its transitions as events with
// the robot's pose, the alarms in force and the readings in telemetry, and
// the channels as Hello announces them (docs/gas.md).
#include <span>
#include <string>
#include <vector>

#include "inspect_robot/v1/link.pb.h"
#include "shared/control/diff_drive.hpp"
#include "shared/gas/alarm_monitor.hpp"
#include "shared/robot/core_event.hpp"

namespace inspect::robot {

class GasBridge {
 public:
  explicit GasBridge(const config::GasConfig& gas) : monitor_(gas) {
    transitions_.reserve(16);
    active_.reserve(16);
  }

  /// Tick: a frame's raw readings at MCU clock `clock_s`; the transitions
  /// wait in transitions() until clearTransitions().
  void update(std::span<const uint16_t> raw, double clock_s) { monitor_.update(raw, clock_s, transitions_); }
  /// No frames since `clock_s` (stale or serial down): the channels go to no_data.
  void noFrames(double clock_s) { monitor_.noFrames(clock_s, transitions_); }
  const std::vector<gas::AlarmTransition>& transitions() const { return transitions_; }
  void clearTransitions() { transitions_.clear(); }

  /// The event of a transition: ALARM_RAISED / ALARM_CLEARED with the alarm
  /// (its times on the robot's clock `now_s`) and where the robot was.
  CoreEvent eventOf(const gas::AlarmTransition& t, double now_s, const control::Pose2& pose) const;
  const std::string& channelName(int channel) const;

  /// Readings (NaN = no data) and the alarms in force; `clock_s` is the MCU
  /// clock of now. Reuses its scratch: no allocation once grown.
  void fillTelemetry(v1::Telemetry& t, double clock_s, double now_s) const;
  /// The channels as announced in Hello.
  std::vector<v1::GasChannelInfo> channels() const;
  const gas::AlarmMonitor& monitor() const { return monitor_; }

 private:
  /// The proto form of a transition or an alarm in force, raised `age_s` ago.
  void alarmOf(const gas::AlarmTransition& t, double age_s, double now_s, v1::GasAlarm& a) const;

  gas::AlarmMonitor monitor_;
  std::vector<gas::AlarmTransition> transitions_;
  mutable std::vector<gas::AlarmTransition> active_;  // fillTelemetry's scratch
};

}  // namespace inspect::robot
