#include "shared/config/robot_config.hpp"

#include <cctype>

namespace inspect::config {

namespace {

// The wide head's mount when its section leaves a key out (config/robot.yaml's values).
constexpr CameraMount kWideCameraDefaults{0.24, 0.0, 0.55, 120.0, 0.0};

CameraMount readCameraMount(const ConfigNode& n, CameraMount m) {
  m.x_m = n.number("x_m", m.x_m, -5.0, 5.0);
  m.y_m = n.number("y_m", m.y_m, -5.0, 5.0);
  m.z_m = n.number("z_m", m.z_m, 0.05, 5.0);
  m.hfov_deg = n.number("hfov_deg", m.hfov_deg, 10.0, 150.0);
  m.tilt_deg = n.number("tilt_deg", m.tilt_deg, -45.0, 45.0);
  return m;
}

}  // namespace

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
  c.camera = readCameraMount(root.optChild("camera"), c.camera);
  if (root.has("wide_camera")) c.wide_camera = readCameraMount(root.optChild("wide_camera"), kWideCameraDefaults);
  const auto mcu = root.optChild("mcu");
  auto& f = c.mcu;
  f.encoder_counts_per_rev = static_cast<int>(mcu.integer("encoder_counts_per_rev", f.encoder_counts_per_rev, 16, 1000000));
  f.speed_kp = mcu.number("speed_kp", f.speed_kp, 0.0, 100.0);
  f.speed_ki = mcu.number("speed_ki", f.speed_ki, 0.0, 1000.0);
  f.speed_ff = mcu.number("speed_ff", f.speed_ff, 0.0, 10.0);
  f.obstacle_stop_m = mcu.number("obstacle_stop_m", f.obstacle_stop_m, 0.0, 2.0);
  f.obstacle_clear_m = mcu.number("obstacle_clear_m", f.obstacle_clear_m, 0.0, 2.5);
  if (f.obstacle_stop_m > 0 && f.obstacle_clear_m <= f.obstacle_stop_m)
    mcu.fail("obstacle_clear_m", "must exceed obstacle_stop_m (the stop's hysteresis)");
  f.ultrasonic_slot_ms = static_cast<int>(mcu.integer("ultrasonic_slot_ms", f.ultrasonic_slot_ms, 10, 100));
  f.ultrasonic_missed_limit = static_cast<int>(mcu.integer("ultrasonic_missed_limit", f.ultrasonic_missed_limit, 1, 100));
  f.gas_shunt_ohm = mcu.number("gas_shunt_ohm", f.gas_shunt_ohm, 10.0, 1000.0);
  if (21e-3 * f.gas_shunt_ohm > 3.3) mcu.fail("gas_shunt_ohm", "21 mA across it exceeds the ADC's 3.3 V");
  f.battery_divider = mcu.number("battery_divider", f.battery_divider, 1.0, 100.0);
  f.battery_low_mv = static_cast<int>(mcu.integer("battery_low_mv", f.battery_low_mv, 0, 60000));
  f.battery_clear_mv = static_cast<int>(mcu.integer("battery_clear_mv", f.battery_clear_mv, 0, 60000));
  if (f.battery_clear_mv <= f.battery_low_mv) mcu.fail("battery_clear_mv", "must exceed battery_low_mv");
  f.ptz_slew_deg_s = mcu.number("ptz_slew_deg_s", f.ptz_slew_deg_s, 1.0, 3600.0);
  f.servo_us_per_deg = mcu.number("servo_us_per_deg", f.servo_us_per_deg, 1.0, 100.0);
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
