#pragma once
// The robot's decision core: the mode and latch machine and the dispatch of
// the server's commands, over the parts in this folder (the state estimate,
// the runs: path tracking, routes, wheel tests; gains staging; the gas
// alarms), and the wheel command of each tick. Pure: every input carries its
// time (`now_s`, monotonic seconds); no I/O, no clock reads.
//
// Which calls run where (as ros2_control marks its interfaces):
// - the 100 Hz tick, no allocation once warm (tests/robot/test_core_allocations.cpp):
//   onSensorFrame, onTimer, commandNow, takeEvents(out), takeAcks, takePtz;
// - the command path, may allocate and block: onCommand (a pushed fuzzy
//   system is compiled there, tens of ms; refused while moving), onLink*,
//   onSerialState;
// - the link's rate (50 Hz): fillTelemetry (no allocation once the message grew).
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "inspect_robot/v1/link.pb.h"
#include "shared/behavior/human_awareness.hpp"
#include "shared/config/control_config.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/control/diff_drive.hpp"
#include "shared/robot/core_event.hpp"
#include "shared/robot/gains_stage.hpp"
#include "shared/robot/gas_bridge.hpp"
#include "shared/robot/route_runner.hpp"
#include "shared/robot/safety_params.hpp"
#include "shared/robot/state_estimate.hpp"
#include "shared/robot/track_runner.hpp"
#include "shared/robot/wheel_test_runner.hpp"
#include "shared/serial/frame_codec.hpp"

namespace inspect::robot {

class RobotCore {
 public:
  /// `scheduler` may be null: tracking with the fuzzy-PID is then refused.
  RobotCore(const config::RobotConfig& robot, const SafetyParams& safety,
            const config::ControlConfig& control = {},
            std::shared_ptr<control::FuzzyGainScheduler> scheduler = nullptr);

  /// A valid sensor frame arrived (100 Hz): updates the estimate, runs the
  /// tick, returns the wheel command to send.
  serial::WheelCommand onSensorFrame(const serial::SensorFrame& f, double now_s);
  /// Periodic check (every ~10 ms). Returns a command to send when sensor
  /// frames are stale (the loop is then timer-driven and commands zero).
  std::optional<serial::WheelCommand> onTimer(double now_s);

  /// The command for the current state, to send at once after a command or
  /// link change (no slew step is taken).
  serial::WheelCommand commandNow();

  /// Turns on human awareness (people tracking and the Eq 9 speed factor).
  void setAwareness(std::unique_ptr<behavior::HumanAwareness> a) { awareness_ = std::move(a); }
  /// Human awareness (its tracks, its config); null when off.
  const behavior::HumanAwareness* awareness() const { return awareness_.get(); }

  /// A camera picture's people (the robot at its present pose: the
  /// picture's ~0.1 s age is in the fusion's bearing noise).
  void onCameraLook(const behavior::CameraLook& look) {
    if (awareness_) awareness_->observeCamera(estimate_.pose(), look);
  }

  /// The TCP link came up (handshake accepted) / went down.
  void onLinkUp(double now_s);
  void onLinkDown(double now_s, const std::string& why);
  /// Any heartbeat or command from the server.
  void onLinkActivity(double now_s);
  /// A command from the server; returns the Ack to send.
  v1::Ack onCommand(const v1::Command& cmd, double now_s);
  /// Serial device state.
  void onSerialState(bool open, double now_s);
  /// Records the serial decoder counters for telemetry.
  void setSerialCounters(const serial::DecoderCounters& rx, uint64_t bytes_tx, uint64_t frames_tx);

  void fillTelemetry(v1::Telemetry& t, double now_s) const;
  /// Moves the events raised since the last call into `out` (swapping
  /// buffers: a caller that keeps `out` allocates nothing).
  void takeEvents(std::vector<CoreEvent>& out) { events_.takeInto(out); }
  /// The same, into a new vector (for tests and tools); none raised: an
  /// empty vector, and the core keeps its buffer.
  std::vector<CoreEvent> takeEvents() {
    std::vector<CoreEvent> out;
    if (!events_.empty()) events_.takeInto(out);
    return out;
  }
  /// Moves out Acks the core produced on its own (COMPLETED of a track run or a route).
  std::vector<v1::Ack> takeAcks();
  /// Moves out camera set-points of inspection points reached since the last call.
  std::vector<v1::Ptz> takePtz();
  /// The gas channels as announced in Hello.
  std::vector<v1::GasChannelInfo> gasChannels() const { return gas_.channels(); }
  const gas::AlarmMonitor& gasMonitor() const { return gas_.monitor(); }

  /// Tracking gains in force and their version (0 = the control config's;
  /// +1 per applied GainsUpdate), and the fuzzy system's name.
  const control::GainSet& gains() const { return gains_.gains(); }
  uint32_t gainsVersion() const { return gains_.version(); }
  const std::string& fisName() const { return gains_.fisName(); }
  void setFisName(std::string name) { gains_.setFisName(std::move(name)); }

  v1::Mode mode() const { return mode_; }
  uint32_t faults() const { return faults_; }
  const control::Pose2& pose() const { return estimate_.pose(); }
  control::Twist commandedTwist() const { return cmd_twist_; }
  /// Distance to the nearest tracked person (centre), none without one or without awareness.
  std::optional<double> nearestPersonM() const {
    if (!awareness_ || !awareness_->last().person) return std::nullopt;
    return awareness_->last().distance_m;
  }
  /// The navigator of the current go_to command; null when none.
  const navigation::Navigator* navigator() const { return route_.navigator(); }

  static constexpr int kMaxGoals = RouteRunner::kMaxGoals;
  static constexpr double kWheelTestRadius_m = WheelTestRunner::kRadius_m;
  static constexpr double kDefaultNavSpeed_m_s = RouteRunner::kDefaultSpeed_m_s;

 private:
  bool moving() const {
    return mode_ == v1::TELEOP || mode_ == v1::TRACKING || mode_ == v1::NAVIGATING || mode_ == v1::WHEEL_TEST;
  }
  bool latched() const { return mode_ == v1::ESTOP || mode_ == v1::FAILSAFE; }
  v1::Ack teleop(const v1::Command& cmd, double now_s);
  v1::Ack startTrack(const v1::Command& cmd);
  v1::Ack startWheelTest(const v1::Command& cmd);
  v1::Ack startGoTo(const v1::Command& cmd);
  /// Puts staged gains in force (start of a tick, or of a track run).
  void applyPendingGains();
  /// Why a track, go_to or wheel test command cannot start now ("" when it can).
  std::string autonomyRefusal() const;
  /// Ends tracking, navigation and the wheel test (the operator or a safety stop takes over).
  void endAutonomy();
  /// A run ended in a tick: its Ack, the wheels to zero, IDLE.
  void finishRun(RunEnd end);
  void setMode(v1::Mode m, const std::string& why);
  void raise(uint32_t fault, const std::string& why);
  void clear(uint32_t fault, const std::string& why);
  void latchFailsafe(const std::string& why);
  void clearSetpoint() {
    teleop_.setpoint = {};
    teleop_.time_s = -1.0;
  }
  /// Announces gas alarm transitions and applies the configured reaction.
  void onGasTransitions(double now_s);
  void checkTimeouts(double now_s);
  /// The link has been silent for longer than link_timeout_s: LINK_LOST, and
  /// FAILSAFE if the robot was moving when the silence began.
  void checkLinkSilence(double now_s);
  /// Whether the robot was moving when the link last carried anything (a
  /// teleop set-point that went stale in the silence does not count as a stop).
  bool movingAtLinkLoss() const { return moving() || teleop_.stale_stop_s >= link_.last_activity_s; }
  serial::WheelCommand computeCommand(double dt_s);
  /// cmd_wheels_ as the MCU command (and cmd_twist_ from it).
  serial::WheelCommand wheelCommand(bool enable);
  /// Tracking: 1 when nothing is close ahead, down to 0 at safety.obstacle_stop_m (front sonars).
  double obstacleFactor();
  /// The Eq 9 speed factor of the people around (1 without awareness).
  double personFactor() const { return awareness_ ? awareness_->last().speed_factor : 1.0; }

  config::RobotConfig robot_;
  SafetyParams safety_;
  config::ControlConfig control_;  // with the robot's geometry applied

  // The mode and latch machine.
  v1::Mode mode_ = v1::IDLE;
  uint32_t faults_ = 0;
  std::string latch_reason_;
  uint64_t last_command_id_ = 0;
  struct Link {
    bool up = false;
    double last_activity_s = 0.0;
  } link_;
  struct Teleop {
    control::Twist setpoint;
    double time_s = -1.0;        // when the set-point came (< 0: none)
    double stale_stop_s = -1.0;  // when a stale set-point last stopped the robot
  } teleop_;
  struct Serial {
    bool open = false;
    serial::DecoderCounters rx;
    uint64_t bytes_tx = 0;
    uint64_t frames_tx = 0;
  } serial_;

  // The parts.
  StateEstimate estimate_;
  GainsStage gains_;
  TrackRunner track_;
  WheelTestRunner wheel_test_;
  RouteRunner route_;
  GasBridge gas_;
  std::unique_ptr<behavior::HumanAwareness> awareness_;
  bool obstacle_stopped_ = false;
  /// When the core last ran (a tick or a frame): a gap in it is this
  /// process not being scheduled, told apart from a silent MCU in the
  /// SENSOR_STALE text.
  double last_run_s_ = -1.0;

  // Output.
  control::Twist cmd_twist_;
  control::WheelSpeeds cmd_wheels_;
  EventLog events_;
  std::vector<v1::Ack> acks_;
};

}  // namespace inspect::robot
