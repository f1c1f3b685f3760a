#pragma once
// The robot's decision core: modes, safety latches, teleop set-point, path
// tracking, navigation to goals, odometry and wheel commands. Pure: every
// input carries its time (`now_s`, monotonic seconds); no I/O, no clock
// reads, no allocation in the per-tick path.
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "inspect/v1/link.pb.h"
#include "robot_client/client_config.hpp"
#include "shared/behavior/human_awareness.hpp"
#include "shared/config/control_config.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/control/gain_set.hpp"
#include "shared/control/trajectory_tracker.hpp"
#include "shared/control/wheel_profile.hpp"
#include "shared/control/diff_drive.hpp"
#include "shared/gas/alarm_monitor.hpp"
#include "shared/navigation/navigator.hpp"
#include "shared/serial/frame_codec.hpp"

namespace inspect::client {

/// What the core wants announced to the server as an Event.
struct CoreEvent {
  v1::Event::Kind kind = v1::Event::INFO;
  std::string text;
  std::optional<v1::GasAlarm> gas_alarm;  // ALARM_RAISED / ALARM_CLEARED
  std::optional<v1::Gains> gains;         // GAINS_APPLIED (with gains_version)
  uint32_t gains_version = 0;
};

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
  /// Moves out the events raised since the last call.
  std::vector<CoreEvent> takeEvents();
  /// Moves out Acks the core produced on its own (COMPLETED of a track run or a route).
  std::vector<v1::Ack> takeAcks();
  /// Moves out camera set-points of inspection points reached since the last call.
  std::vector<v1::Ptz> takePtz();
  /// The gas channels as announced in Hello.
  std::vector<v1::GasChannelInfo> gasChannels() const;
  const gas::AlarmMonitor& gasMonitor() const { return gas_; }

  /// Tracking gains in force and their version (0 = the control config's;
  /// +1 per applied GainsUpdate), and the fuzzy system's name.
  const control::GainSet& gains() const { return gains_; }
  uint32_t gainsVersion() const { return gains_version_; }
  const std::string& fisName() const { return fis_name_; }
  void setFisName(std::string name) { fis_name_ = std::move(name); }

  v1::Mode mode() const { return mode_; }
  uint32_t faults() const { return faults_; }
  const control::Pose2& pose() const { return pose_; }
  control::Twist commandedTwist() const { return cmd_twist_; }
  /// The navigator of the current (or last) go_to command; null before the first one.
  const navigation::Navigator* navigator() const { return navigator_.get(); }

  /// Most goals one go_to command may carry.
  static constexpr int kMaxGoals = 100;
  /// A wheel test ends (FAILED) once the robot is this far from where it began.
  static constexpr double kWheelTestRadius_m = 1.0;
  /// Cruise speed of a go_to command that gives none (clamped to the robot's limit).
  static constexpr double kDefaultNavSpeed_m_s = 0.5;

 private:
  bool moving() const {
    return mode_ == v1::TELEOP || mode_ == v1::TRACKING || mode_ == v1::NAVIGATING || mode_ == v1::WHEEL_TEST;
  }
  v1::Ack startTrack(const v1::Command& cmd);
  v1::Ack startWheelTest(const v1::Command& cmd);
  /// Checks a GainsUpdate and stages it for the next tick.
  v1::Ack stageGains(const v1::Command& cmd);
  /// Puts staged gains in force (start of a tick, or of a track run).
  void applyPendingGains();
  /// One wheel-test tick: the profile's set-point, or its end.
  void wheelTestStep(double dt_s);
  v1::Ack startGoTo(const v1::Command& cmd);
  /// Why a track or go_to command cannot start now ("" when it can).
  std::string autonomyRefusal() const;
  /// Ends tracking and navigation (the operator or a safety stop takes over).
  void endAutonomy();
  /// One navigation tick: the navigator's twist scaled by Eq 9; advances the route.
  control::Twist navigationTwist(double dt_s);
  void setMode(v1::Mode m, const std::string& why);
  void raise(uint32_t fault, const std::string& why);
  void clear(uint32_t fault, const std::string& why);
  void latchFailsafe(const std::string& why);
  /// The proto form of a monitor transition or alarm in force (`age_s` since
  /// it was raised; pose and robot_time_us are the caller's).
  void gasAlarmOf(const gas::AlarmTransition& t, double age_s, double now_s, v1::GasAlarm& a) const;
  /// Announces gas alarm transitions and applies the configured reaction.
  void onGasTransitions(double now_s);
  /// The navigation goal `i` was reached: dwell, PTZ preset.
  void arriveAt(std::size_t i);
  /// Turns the route round: back through the goals already reached to the start.
  void startRetreat(const std::string& why);
  void checkTimeouts(double now_s);
  /// The link has been silent for longer than link_timeout_s: LINK_LOST, and
  /// FAILSAFE if the robot was moving when the silence began.
  void checkLinkSilence(double now_s);
  /// Whether the robot was moving when the link last carried anything (a
  /// teleop set-point that went stale in the silence does not count as a stop).
  bool movingAtLinkLoss() const { return moving() || stale_stop_s_ >= last_link_activity_s_; }
  serial::WheelCommand computeCommand(double dt_s);
  /// cmd_wheels_ as the MCU command (and cmd_twist_ from it).
  serial::WheelCommand wheelCommand(bool enable);
  /// Tracking: 1 when nothing is close ahead, down to 0 at safety.obstacle_stop_m (front sonars).
  double obstacleFactor();

  config::RobotConfig robot_;
  SafetyParams safety_;
  v1::Mode mode_ = v1::IDLE;
  uint32_t faults_ = 0;
  std::string latch_reason_;

  // Link.
  bool link_up_ = false;
  double last_link_activity_s_ = 0.0;

  // Teleop set-point.
  control::Twist setpoint_;
  double setpoint_time_s_ = -1.0;
  double stale_stop_s_ = -1.0;  // when a stale teleop set-point last stopped the robot
  uint64_t last_command_id_ = 0;

  // Sensors and estimate.
  bool have_frame_ = false;
  bool serial_open_ = false;
  double last_frame_s_ = -1.0;
  serial::SensorFrame last_frame_;
  std::array<int32_t, 2> last_disp_{};
  int16_t heading0_ = 0;
  uint32_t last_mcu_ms_ = 0;
  uint64_t mcu_time_us_ = 0;  // MCU clock since the first frame (telemetry mcu_time_us)
  control::Pose2 pose_;
  control::WheelSpeeds measured_;
  double rate_window_start_s_ = 0.0;
  int rate_count_ = 0;
  double sensor_rate_hz_ = 0.0;

  // Output.
  control::Twist cmd_twist_;
  control::WheelSpeeds cmd_wheels_;
  serial::DecoderCounters serial_rx_;
  uint64_t bytes_tx_ = 0;
  uint64_t frames_tx_ = 0;

  std::vector<CoreEvent> events_;
  std::vector<v1::Ack> acks_;

  // Trajectory tracking.
  config::ControlConfig control_;
  std::shared_ptr<control::FuzzyGainScheduler> scheduler_;
  std::unique_ptr<control::TrajectoryTracker> tracker_;
  uint64_t track_command_id_ = 0;
  std::string track_controller_;
  control::TrackerOutput track_out_;
  double track_max_pos_m_ = 0.0;
  double track_max_ang_rad_ = 0.0;
  control::PidGains track_gains_;

  // Tracking gains (Command.gains).
  control::GainSet gains_;
  uint32_t gains_version_ = 0;
  std::string fis_name_;
  struct PendingGains {
    control::GainSet gains;
    uint32_t version = 0;
    std::shared_ptr<control::FuzzyGainScheduler> scheduler;  // null = keep the fuzzy system
    std::string fis_name;
    std::string source;
  };
  std::optional<PendingGains> pending_gains_;

  // Wheel test (Command.wheel_test).
  std::unique_ptr<control::WheelProfile> wheel_test_;
  uint64_t wheel_test_id_ = 0;
  double wheel_test_t_s_ = 0.0;
  control::Pose2 wheel_test_start_;
  double wheel_test_progress_ = 0.0;
  std::string wheel_test_name_;

  // Navigation (Command.go_to).
  std::unique_ptr<navigation::Navigator> navigator_;
  std::vector<navigation::Vec2> goals_;
  std::size_t goal_index_ = 0;
  uint64_t nav_command_id_ = 0;
  uint32_t nav_switches_done_ = 0;  // automaton switches of the goals already reached
  double goal_distance_m_ = 0.0;
  double nav_stall_clock_s_ = 0.0;  // time allowed to move (dt x Eq 9 factor) since the command
  double nav_best_m_ = std::numeric_limits<double>::infinity();  // closest to the current goal so far
  double nav_best_clock_s_ = 0.0;
  control::Twist nav_twist_;          // the last tick's navigation twist (after Eq 9)
  struct GoalInfo {
    double dwell_s = 0.0;
    bool has_ptz = false;
    v1::Ptz ptz;
    std::string label;
  };
  std::vector<GoalInfo> goal_info_;   // per goal of goals_
  std::string route_name_;
  bool route_inspection_ = false;
  navigation::Vec2 route_start_;      // where the route began (retreat target)
  double dwell_left_s_ = 0.0;         // > 0: dwelling at the goal just reached
  std::string dwell_label_;           // its label
  bool final_dwell_ = false;          // dwelling at the last point: the route completes after it
  bool gas_hold_ = false;             // stopped and holding after a gas HIGH alarm
  bool retreating_ = false;           // going back after a gas HIGH alarm
  std::string retreat_reason_;
  std::vector<v1::Ptz> ptz_out_;

  // Gas alarms.
  gas::AlarmMonitor gas_;
  double gas_clock_s_ = 0.0;  // MCU time since the first frame (the alarm monitor's clock)
  std::vector<gas::AlarmTransition> gas_out_;
  mutable std::vector<gas::AlarmTransition> gas_active_;  // fillTelemetry's scratch

  // Human awareness.
  std::unique_ptr<behavior::HumanAwareness> awareness_;
  bool obstacle_stopped_ = false;
  double mcu_clock_s_ = 0.0;  // MCU time since the first frame
};

}  // namespace inspect::client
