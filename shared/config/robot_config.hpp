#pragma once
// Robot geometry, limits and sensor layout (config/robot.yaml), shared by
// robot_client and mcu_sim. Defaults are the paper's robot (PAPER_DIGEST.md).
#include <array>
#include <optional>
#include <string>

#include "shared/config/config_node.hpp"
#include "shared/config/gas_config.hpp"
#include "shared/control/diff_drive.hpp"

namespace inspect::config {

/// Paper geometry (Fig 2): r, L, L1, L2, L3.
struct RobotGeometry {
  double wheel_radius_m = 0.200;
  double track_m = 0.438;
  double l1_m = 0.214;   // front axle to centre of mass
  double l2_m = 0.172;   // centre of mass to rear axle
  double l3_m = 0.046;   // rear axle to rear wheel rotating shaft
  double mass_kg = 34.0;
  double body_radius_m = 0.35;  // collision circle around the axle midpoint
};

/// Motion limits enforced by robot_client (and by the MCU on wheel speed).
struct RobotLimits {
  double max_wheel_speed_rad_s = 5.0;   // 1.0 m/s at r = 0.2 m
  double max_wheel_accel_rad_s2 = 10.0;
  double max_v_m_s = 1.0;
  double max_w_rad_s = 2.0;
};

/// Hub motor + driver as a first-order plant (used by the simulator and the tuner).
struct MotorModel {
  double time_constant_s = 0.20;
  double speed_noise_m_s = 0.002;    // encoder speed error (paper: +-0.002 m/s)
  double heading_noise_rad = 0.002;  // heading sensor error (paper: +-0.002 rad)
};

/// One ultrasonic transducer's mounting pose in the robot frame.
struct UltrasonicMount {
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;
};

/// Where a sensor is and where it looks, in the frame `robot` is given in.
inline control::Pose2 mountPose(const control::Pose2& robot, const UltrasonicMount& m) {
  const double c = std::cos(robot.theta_rad), s = std::sin(robot.theta_rad);
  return {robot.x_m + c * m.x_m - s * m.y_m, robot.y_m + s * m.x_m + c * m.y_m, robot.theta_rad + m.yaw_rad};
}

/// The 4 ultrasonic sensors (front-left, front-right, left, right).
struct UltrasonicConfig {
  double min_range_m = 0.02;
  double max_range_m = 4.5;
  double beam_width_rad = 0.52;   // full cone angle (30 deg)
  double noise_m = 0.03;          // paper: +-0.03 m
  std::array<UltrasonicMount, 4> mounts{{{0.30, 0.12, 0.0}, {0.30, -0.12, 0.0}, {0.0, 0.25, 1.5707963267948966},
                                         {0.0, -0.25, -1.5707963267948966}}};
};

/// The PTZ camera's mount: where the pan/tilt head sits on the robot and what
/// the lens takes in (mcu_sim renders this camera's view, sim/camera_view.hpp).
/// Pan turns it about the vertical through the mount (CCW positive), tilt about
/// its horizontal axis (up positive); both 0 = looking straight ahead.
struct CameraMount {
  double x_m = 0.20;      // ahead of the axle midpoint
  double y_m = 0.0;       // left of the centre line
  double z_m = 0.60;      // lens height above the floor
  double hfov_deg = 60.0; // horizontal field of view (the vertical one follows from the picture's aspect)
  double tilt_deg = 0.0;  // the head's own tilt on the robot, up positive; the PTZ's tilt adds to it
};

/// The MCU firmware's own settings (the `mcu` section; firmware/, docs/firmware.md):
/// its hub-motor speed loops, encoders, anti-collision stop, sensors' electrical
/// interfaces and the camera mount's servos. scripts/build_firmware.sh turns
/// them into the firmware's settings header.
struct McuConfig {
  int encoder_counts_per_rev = 16384;  // quadrature counts per wheel revolution (4096 lines x 4)
  double speed_kp = 0.2;               // duty per rad/s of wheel speed error (docs/firmware.md)
  double speed_ki = 2.0;               // duty per rad of integrated error
  double speed_ff = 0.154;             // feed-forward duty per rad/s of set-point (1 / no-load speed at full duty)
  double obstacle_stop_m = 0.15;       // forward motion stopped while a front range is under this (0 = off)
  double obstacle_clear_m = 0.20;      // ... until both front ranges are above this
  int ultrasonic_slot_ms = 30;         // one sensor fired per slot, in turn (4.5 m and back: 26 ms)
  int ultrasonic_missed_limit = 3;     // slots in a row without an echo pulse: ULTRASONIC
  double gas_shunt_ohm = 150.0;        // 4-20 mA gas transmitters into this shunt at the ADC
  double battery_divider = 11.0;       // battery voltage / ADC pin voltage
  int battery_low_mv = 22200;          // BATTERY_LOW below this
  int battery_clear_mv = 22600;        // ... until above this
  double ptz_slew_deg_s = 120.0;       // servo set-point slew limit
  double servo_us_per_deg = 11.11;     // servo pulse per degree (1000 us per 90 degrees)
};

struct RobotConfig {
  RobotGeometry geometry;
  RobotLimits limits;
  MotorModel motor;
  UltrasonicConfig ultrasonic;
  CameraMount camera;                      // the PTZ head (its pan and tilt move on it)
  std::optional<CameraMount> wide_camera;  // the second head, wide and fixed (`wide_camera`; absent = none)
  McuConfig mcu;
  GasConfig gas;  // the `gas` section (none when absent; defaultGasConfig() = config/robot.yaml's)
};

/// Reads a robot config; missing keys take the defaults above. Throws ConfigError.
RobotConfig loadRobotConfig(const ConfigNode& root);
RobotConfig loadRobotConfigFile(const std::string& path);

}  // namespace inspect::config
