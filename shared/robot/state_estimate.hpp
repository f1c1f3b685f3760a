#pragma once
// What the robot knows of itself from the MCU's sensor frames: the pose by
// odometry with the IMU heading, the measured wheel speeds, the last frame
// (sonars, line sensor, gas, battery, MCU faults), the frame rate, and the
// MCU clock. Every call here is part of the 100 Hz tick: no allocation.
#include <array>
#include <cstdint>

#include "shared/config/robot_config.hpp"
#include "shared/control/diff_drive.hpp"
#include "shared/serial/messages.hpp"

namespace inspect::robot {

/// The MCU's time since the first frame, one clock read two ways.
struct McuClock {
  /// Sum of the frame-to-frame steps of mcu_time_ms, and across a serial
  /// outage (after which the MCU's count restarts) the outage's length, so a
  /// series sampled on it shows the gap (Telemetry.mcu_time_us).
  uint64_t elapsed_us = 0;
  /// Sum of the steps, each clamped to [0, 0.1] s: the clock of the people
  /// tracker and the gas alarms, so that their durations mean the same when
  /// the simulator runs faster than real time and a late frame is one step.
  double control_s = 0.0;
};

class StateEstimate {
 public:
  /// A valid frame arrived at `now_s` (this process's monotonic time);
  /// returns the MCU time since the previous frame (0.01 s for the first
  /// frame after start or after the serial line came back).
  double onFrame(const serial::SensorFrame& f, double now_s);
  /// The serial line closed: the next frame re-anchors the odometry.
  void lose() { have_frame_ = false; }

  bool haveFrame() const { return have_frame_; }
  /// When the last frame arrived (< 0 before the first).
  double lastFrameS() const { return last_frame_s_; }
  const serial::SensorFrame& lastFrame() const { return last_frame_; }
  const control::Pose2& pose() const { return pose_; }
  const control::WheelSpeeds& measured() const { return measured_; }
  const McuClock& clock() const { return clock_; }
  /// Frames per second over the last full second (0 before).
  double sensorRateHz() const { return sensor_rate_hz_; }

  /// The nearest echo of a front sonar (mounted within 0.3 rad of ahead), m;
  /// infinity when none has one.
  double nearestFrontM(const config::UltrasonicConfig& sonars) const;

 private:
  bool have_frame_ = false;
  double last_frame_s_ = -1.0;
  serial::SensorFrame last_frame_;
  std::array<int32_t, 2> last_disp_{};
  int16_t heading0_ = 0;
  uint32_t last_mcu_ms_ = 0;
  McuClock clock_;
  control::Pose2 pose_;
  control::WheelSpeeds measured_;
  double rate_window_start_s_ = 0.0;
  int rate_count_ = 0;
  double sensor_rate_hz_ = 0.0;
};

}  // namespace inspect::robot
