#pragma once
// Rigid-body plant of the robot: two hub motors as first-order lags toward
// their set-points, unicycle kinematics (shared/control/diff_drive.hpp) and a
// circular body that cannot pass through walls. Pure: state, command, dt in,
// next state out.
#include "shared/config/robot_config.hpp"
#include "shared/control/diff_drive.hpp"
#include "shared/control/plant_model.hpp"
#include "sim/world_names.hpp"

namespace inspect::sim {

/// The plant robot.yaml describes: both wheels gain 1, its motor time
/// constant, no dead time, saturation at limits.max_wheel_speed_rad_s.
control::PlantModel nominalPlant(const config::RobotConfig& robot);

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
  /// The motors of `world.plant` when the world gives one, else the nominal
  /// plant of the robot config (nominalPlant()).
  RobotPlant(const config::RobotConfig& robot, const World& world);
  RobotPlant(const config::RobotConfig& robot, const World& world, const control::PlantModel& motors);

  /// Advances `s` by dt_s toward gain x the wheel set-points (clamped to
  /// +-saturation). Dead time is the caller's (control::SetpointDelay).
  PlantStep step(const PlantState& s, const control::WheelSpeeds& setpoint, double dt_s) const;
  /// Set-point after the plant's speed limit.
  control::WheelSpeeds clampSetpoint(const control::WheelSpeeds& sp) const;
  const control::PlantModel& motors() const { return motors_; }

 private:
  double wheel_radius_m_;
  double track_m_;
  double body_radius_m_;
  control::PlantModel motors_;
  const World& world_;
};

}  // namespace inspect::sim
