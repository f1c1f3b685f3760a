#pragma once
// Drives a RobotCore with sensor frames at 100 Hz; the frames report whatever
// the core commanded (an ideal MCU), so odometry integrates the commands.
#include <cmath>
#include <cstdint>

#include "shared/robot/robot_core.hpp"
#include "shared/config/control_config.hpp"

namespace inspect::test {

struct CoreHarness {
  config::RobotConfig robot;
  robot::SafetyParams safety;
  config::ControlConfig control;
  robot::RobotCore core;
  serial::SensorFrame f;
  double t = 0.0;
  double disp_l = 0, disp_r = 0;
  serial::WheelCommand last;

  /// The core with its default tracking controllers.
  CoreHarness() : core(robot, safety) { start(); }
  /// The core with the controllers (and fuzzy gain scheduler) of `c`.
  explicit CoreHarness(config::ControlConfig c)
      : control(std::move(c)), core(robot, safety, control, config::loadScheduler(control)) {
    start();
  }

  /// One 10 ms frame (with a heartbeat from the server unless told otherwise).
  void step(bool heartbeat = true) {
    t += 0.01;
    if (heartbeat) core.onLinkActivity(t);
    f.mcu_time_ms = static_cast<uint32_t>(std::lround(t * 1000));
    disp_l += last.left_mrad_s * 1e-3 * robot.geometry.wheel_radius_m * 0.01;
    disp_r += last.right_mrad_s * 1e-3 * robot.geometry.wheel_radius_m * 0.01;
    f.wheel_disp_0p1mm = {static_cast<int32_t>(std::lround(disp_l * 1e4)),
                          static_cast<int32_t>(std::lround(disp_r * 1e4))};
    f.wheel_speed_mrad_s = {last.left_mrad_s, last.right_mrad_s};
    last = core.onSensorFrame(f, t);
  }
  void run(double seconds, bool heartbeat = true) {
    const int n = static_cast<int>(std::lround(seconds / 0.01));
    for (int i = 0; i < n; ++i) step(heartbeat);
  }

 private:
  void start() {
    f.ultrasonic_mm.fill(serial::kNoEcho);  // nothing in range unless a test says so
    core.onSerialState(true, 0.0);
    core.onLinkUp(0.0);
  }
};

}  // namespace inspect::test
