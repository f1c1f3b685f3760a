#include "sim/robot_plant.hpp"

#include <algorithm>
#include <cmath>

#include "shared/control/first_order.hpp"

namespace inspect::sim {

control::PlantModel nominalPlant(const config::RobotConfig& robot) {
  control::WheelMotorModel m;
  m.gain = 1.0;
  m.time_constant_s = robot.motor.time_constant_s;
  m.dead_time_s = 0.0;
  m.saturation_rad_s = robot.limits.max_wheel_speed_rad_s;
  return {m, m};
}

namespace {
control::PlantModel worldPlant(const config::RobotConfig& robot, const World& world) {
  if (!world.plant) return nominalPlant(robot);
  control::PlantModel p = *world.plant;
  for (auto* m : {&p.left, &p.right})
    if (!(m->saturation_rad_s > 0.0)) m->saturation_rad_s = robot.limits.max_wheel_speed_rad_s;
  return p;
}
}  // namespace

RobotPlant::RobotPlant(const config::RobotConfig& robot, const World& world)
    : RobotPlant(robot, world, worldPlant(robot, world)) {}

RobotPlant::RobotPlant(const config::RobotConfig& robot, const World& world, const control::PlantModel& motors)
    : wheel_radius_m_(robot.geometry.wheel_radius_m),
      track_m_(robot.geometry.track_m),
      body_radius_m_(robot.geometry.body_radius_m),
      motors_(motors),
      world_(world) {}

control::WheelSpeeds RobotPlant::clampSetpoint(const control::WheelSpeeds& sp) const {
  auto clamp = [](double v, double lim) { return std::isfinite(v) ? std::clamp(v, -lim, lim) : 0.0; };
  return {clamp(sp.left_rad_s, motors_.left.saturation_rad_s), clamp(sp.right_rad_s, motors_.right.saturation_rad_s)};
}

PlantStep RobotPlant::step(const PlantState& s, const control::WheelSpeeds& setpoint, double dt_s) const {
  const auto sp = clampSetpoint(setpoint);
  // Each motor's speed and the angle it turned over the step, exactly.
  const auto l =
      control::firstOrderStep(s.wheel.left_rad_s, motors_.left.gain * sp.left_rad_s, motors_.left.time_constant_s, dt_s);
  const auto r = control::firstOrderStep(s.wheel.right_rad_s, motors_.right.gain * sp.right_rad_s,
                                         motors_.right.time_constant_s, dt_s);
  const double d_left_m = l.integral * wheel_radius_m_;
  const double d_right_m = r.integral * wheel_radius_m_;

  PlantStep out;
  out.state = s;
  out.state.wheel = {l.value, r.value};
  out.state.wheel_travel_left_m += d_left_m;
  out.state.wheel_travel_right_m += d_right_m;

  // Eqs 1-3 in the project convention, midpoint-integrated over the 1 ms step.
  const control::Pose2 next = control::integrateOdometry(s.pose, d_left_m, d_right_m, track_m_);
  const double c_next = clearance(world_, {next.x_m, next.y_m});
  const double c_now = clearance(world_, {s.pose.x_m, s.pose.y_m});
  // A step into a wall is refused; one that increases clearance is always
  // allowed so that a robot touching a wall can back away.
  if (c_next < body_radius_m_ && c_next < c_now) {
    out.blocked = true;
    out.state.pose.theta_rad = next.theta_rad;  // a circle can always turn in place
    out.clearance_m = c_now;
  } else {
    out.state.pose = next;
    out.clearance_m = c_next;
  }
  return out;
}

}  // namespace inspect::sim
