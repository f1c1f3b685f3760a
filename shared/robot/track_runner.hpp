#pragma once
// A path tracked by the robot (Command.track): the trajectory tracker
// (Eqs 10-13) with its wheel loop (PID Eq 14, fuzzy-PID Eqs 14-15, or
// direct), started from the robot's pose, stepped each tick with the Eq 9
// speed factor, and its errors for telemetry.
#include <cstdint>
#include <memory>
#include <string>

#include "inspect_robot/v1/link.pb.h"
#include "shared/config/control_config.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/control/gain_set.hpp"
#include "shared/control/trajectory_tracker.hpp"
#include "shared/robot/core_event.hpp"

namespace inspect::robot {

class TrackRunner {
 public:
  /// Command path, allocates: builds the path of `t` from `pose` with the
  /// gains in force. Returns "" and sets `what` (the path and the
  /// controller, for the mode change) when it started, else why not.
  std::string start(const v1::Track& t, uint64_t command_id, const control::Pose2& pose,
                    const config::ControlConfig& control, const control::GainSet& gains,
                    const std::shared_ptr<control::FuzzyGainScheduler>& scheduler,
                    const config::RobotLimits& limits, std::string& what);
  bool active() const { return tracker_ != nullptr; }
  /// Tick: one step with speed factor `factor` (Eq 9 and obstacles); the
  /// wheel set-point is command(). Returns the end of the run when the path
  /// is complete.
  std::optional<RunEnd> step(const control::Pose2& pose, const control::WheelSpeeds& measured, double factor,
                             double dt_s);
  const control::WheelSpeeds& command() const { return out_.command; }
  /// New gains (and fuzzy system, if not null) on the path being tracked.
  void setGains(const control::GainSet& gains, const std::shared_ptr<control::FuzzyGainScheduler>& scheduler);
  /// The operator or a safety stop took over; the last errors stay for telemetry.
  void end() {
    tracker_.reset();
    command_id_ = 0;
  }
  void fillTelemetry(v1::Telemetry& t) const;

 private:
  std::unique_ptr<control::TrajectoryTracker> tracker_;
  uint64_t command_id_ = 0;
  std::string controller_;
  control::TrackerOutput out_;
  double max_pos_m_ = 0.0;
  double max_ang_rad_ = 0.0;
  control::PidGains gains_;
  bool ran_ = false;  // a run has started: until then the tracking fields are unknown (left out)
};

}  // namespace inspect::robot
