#include "shared/config/robot_config.hpp"

#include <cctype>

namespace inspect::config {

RobotConfig loadRobotConfig(const ConfigNode& root) {
  RobotConfig c;
  const auto g = root.optChild("geometry");
  c.geometry.wheel_radius_m = g.number("wheel_radius_m", c.geometry.wheel_radius_m, 0.01, 2.0);
  c.geometry.track_m = g.number("track_m", c.geometry.track_m, 0.05, 5.0);
  c.geometry.l1_m = g.number("l1_m", c.geometry.l1_m, 0.0, 5.0);
  c.geometry.l2_m = g.number("l2_m", c.geometry.l2_m, 0.0, 5.0);
  c.geometry.l3_m = g.number("l3_m", c.geometry.l3_m, 0.0, 5.0);
  c.geometry.mass_kg = g.number("mass_kg", c.geometry.mass_kg, 0.1, 1000.0);
  c.geometry.body_radius_m = g.number("body_radius_m", c.geometry.body_radius_m, 0.05, 5.0);

  const auto l = root.optChild("limits");
  c.limits.max_wheel_speed_rad_s = l.number("max_wheel_speed_rad_s", c.limits.max_wheel_speed_rad_s, 0.1, 30.0);
  c.limits.max_wheel_accel_rad_s2 = l.number("max_wheel_accel_rad_s2", c.limits.max_wheel_accel_rad_s2, 0.1, 1000.0);
  c.limits.max_v_m_s = l.number("max_v_m_s", c.limits.max_v_m_s, 0.01, 5.0);
  c.limits.max_w_rad_s = l.number("max_w_rad_s", c.limits.max_w_rad_s, 0.01, 20.0);

  const auto m = root.optChild("motor");
  c.motor.time_constant_s = m.number("time_constant_s", c.motor.time_constant_s, 0.001, 5.0);
  c.motor.speed_noise_m_s = m.number("speed_noise_m_s", c.motor.speed_noise_m_s, 0.0, 1.0);
  c.motor.heading_noise_rad = m.number("heading_noise_rad", c.motor.heading_noise_rad, 0.0, 1.0);

  const auto u = root.optChild("ultrasonic");
  c.ultrasonic.min_range_m = u.number("min_range_m", c.ultrasonic.min_range_m, 0.0, 1.0);
  c.ultrasonic.max_range_m = u.number("max_range_m", c.ultrasonic.max_range_m, 0.1, 20.0);
  if (c.ultrasonic.max_range_m <= c.ultrasonic.min_range_m) u.fail("max_range_m", "must exceed min_range_m");
  c.ultrasonic.beam_width_rad = u.number("beam_width_rad", c.ultrasonic.beam_width_rad, 0.0, 3.0);
  c.ultrasonic.noise_m = u.number("noise_m", c.ultrasonic.noise_m, 0.0, 1.0);
  const auto mounts = u.children("mounts");
  if (!mounts.empty()) {
    if (mounts.size() != 4) u.fail("mounts", "must list exactly 4 sensors (front-left, front-right, left, right)");
    for (std::size_t i = 0; i < 4; ++i) {
      c.ultrasonic.mounts[i].x_m = mounts[i].requireNumber("x_m", -5.0, 5.0);
      c.ultrasonic.mounts[i].y_m = mounts[i].requireNumber("y_m", -5.0, 5.0);
      c.ultrasonic.mounts[i].yaw_rad = mounts[i].requireNumber("yaw_rad", -3.1416, 3.1416);
      (void)mounts[i].string("name", "");
    }
  }
  const auto cam = root.optChild("camera");
  c.camera.x_m = cam.number("x_m", c.camera.x_m, -5.0, 5.0);
  c.camera.y_m = cam.number("y_m", c.camera.y_m, -5.0, 5.0);
  c.camera.z_m = cam.number("z_m", c.camera.z_m, 0.05, 5.0);
  c.camera.hfov_deg = cam.number("hfov_deg", c.camera.hfov_deg, 10.0, 150.0);
  c.camera.tilt_deg = cam.number("tilt_deg", c.camera.tilt_deg, -45.0, 45.0);
  c.gas = loadGasConfig(root.optChild("gas"), root.has("gas"));
  return c;
}

RobotConfig loadRobotConfigFile(const std::string& path) {
  const auto root = ConfigNode::loadFile(path);
  RobotConfig c = loadRobotConfig(root);
  root.checkKnown();
  return c;
}

}  // namespace inspect::config
