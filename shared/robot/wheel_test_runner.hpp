#pragma once
// An open-loop wheel test (Command.wheel_test, docs/tuning.md): holds, steps
// and chirps straight to the wheels for identification, within the robot's
// limits, ended early by anything in the way or a person near.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "inspect_robot/v1/link.pb.h"
#include "shared/config/robot_config.hpp"
#include "shared/control/wheel_profile.hpp"
#include "shared/robot/core_event.hpp"

namespace inspect::robot {

class WheelTestRunner {
 public:
  /// A wheel test ends (FAILED) once the robot is this far from where it began.
  static constexpr double kRadius_m = 1.0;

  /// Command path, allocates: checks the profile of `w` against the robot's
  /// limits and builds it. Returns the profile, or null with `why` set.
  static std::unique_ptr<control::WheelProfile> profileOf(const v1::WheelTest& w, const config::RobotConfig& robot,
                                                         std::string& why);
  /// Starts a checked profile from `pose`; returns its description for the mode change.
  std::string start(std::unique_ptr<control::WheelProfile> profile, const v1::WheelTest& w, uint64_t command_id,
                    const control::Pose2& pose);
  bool active() const { return profile_ != nullptr; }

  /// What may end a test early, read by the core each tick.
  struct Surroundings {
    double nearest_front_m;     // nearest front-sonar echo
    double obstacle_stop_m;     // safety.obstacle_stop_m
    double person_factor;       // Eq 9 speed factor (1 = nobody near)
    double person_distance_m;
  };
  /// Tick: advances the profile; the wheel set-point is at() after it.
  /// Returns the end of the test when it completed or was stopped.
  std::optional<RunEnd> step(double dt_s, const control::Pose2& pose, const Surroundings& s);
  control::WheelSpeeds at() const { return profile_->at(t_s_); }
  void end() {
    profile_.reset();
    command_id_ = 0;
  }
  /// 0..1 of the last (or current) test.
  double progress() const { return progress_; }

 private:
  std::unique_ptr<control::WheelProfile> profile_;
  uint64_t command_id_ = 0;
  double t_s_ = 0.0;
  control::Pose2 start_;
  double progress_ = 0.0;
  std::string name_;
};

}  // namespace inspect::robot
