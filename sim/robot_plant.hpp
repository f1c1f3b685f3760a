#pragma once
// Rigid-body plant of the robot: two hub motors as first-order lags toward
// their set-points, unicycle kinematics (shared/control/diff_drive.hpp) and a
// circular body that cannot pass through walls. Pure: state, command, dt in,
// next state out.
#include "shared/config/robot_config.hpp"
#include "shared/control/diff_drive.hpp"
#include "sim/world.hpp"

namespace inspect::sim {

/// Physical state of the robot.
struct PlantState {
  control::Pose2 pose;          // axle midpoint, world frame
  control::WheelSpeeds wheel;   // actual wheel angular speeds
  double wheel_travel_left_m = 0.0;   // cumulative wheel-surface travel (counts slip at walls)
  double wheel_travel_right_m = 0.0;
};

/// Result of one plant step.
struct PlantStep {
  PlantState state;
  bool blocked = false;     // the translation was refused because the body would overlap a wall
  double clearance_m = 0.0; // body centre to nearest solid edge after the step
};

/// Steps the robot's physics; holds only parameters and the (static) world.
class RobotPlant {
 public:
  RobotPlant(const config::RobotConfig& robot, const World& world);

  /// Advances `s` by dt_s toward the wheel set-points (clamped to +-max wheel speed).
  PlantStep step(const PlantState& s, const control::WheelSpeeds& setpoint, double dt_s) const;
  /// Set-point after the plant's speed limit.
  control::WheelSpeeds clampSetpoint(const control::WheelSpeeds& sp) const;

 private:
  double wheel_radius_m_;
  double track_m_;
  double body_radius_m_;
  double time_constant_s_;
  double max_wheel_rad_s_;
  const World& world_;
};

}  // namespace inspect::sim
