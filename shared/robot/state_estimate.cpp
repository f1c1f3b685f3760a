#include "shared/robot/state_estimate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace inspect::robot {

double StateEstimate::onFrame(const serial::SensorFrame& f, double now_s) {
  double dt_s = 0.01;
  if (!have_frame_) {
    // First frame after start or after the serial line came back: re-anchor
    // displacement; the heading reference is taken once per process.
    if (last_frame_s_ < 0) heading0_ = f.heading_0p1mrad;
    last_disp_ = f.wheel_disp_0p1mm;
    // After an outage the MCU clock restarts the count: carry the outage's
    // length over, so a series sampled on mcu_time_us shows the gap.
    if (last_frame_s_ >= 0) clock_.elapsed_us += static_cast<uint64_t>(std::max(0.0, now_s - last_frame_s_) * 1e6);
  } else {
    const uint32_t step_ms = static_cast<uint32_t>(f.mcu_time_ms - last_mcu_ms_);
    dt_s = static_cast<double>(step_ms) / 1000.0;
    clock_.elapsed_us += static_cast<uint64_t>(step_ms) * 1000u;
    const double dl = static_cast<int32_t>(static_cast<uint32_t>(f.wheel_disp_0p1mm[0]) -
                                           static_cast<uint32_t>(last_disp_[0])) * 1e-4;
    const double dr = static_cast<int32_t>(static_cast<uint32_t>(f.wheel_disp_0p1mm[1]) -
                                           static_cast<uint32_t>(last_disp_[1])) * 1e-4;
    last_disp_ = f.wheel_disp_0p1mm;
    pose_ = control::odometryWithHeading(pose_, dl, dr, (f.heading_0p1mrad - heading0_) * 1e-4);
  }
  have_frame_ = true;
  last_frame_s_ = now_s;
  clock_.control_s += std::clamp(dt_s, 0.0, 0.1);
  last_mcu_ms_ = f.mcu_time_ms;
  last_frame_ = f;
  measured_ = {f.wheel_speed_mrad_s[0] * 1e-3, f.wheel_speed_mrad_s[1] * 1e-3};
  if (++rate_count_, now_s - rate_window_start_s_ >= 1.0) {
    sensor_rate_hz_ = rate_count_ / (now_s - rate_window_start_s_);
    rate_window_start_s_ = now_s;
    rate_count_ = 0;
  }
  return dt_s;
}

double StateEstimate::nearestFrontM(const config::UltrasonicConfig& sonars) const {
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < sonars.mounts.size() && i < serial::kUltrasonicCount; ++i) {
    const uint16_t mm = last_frame_.ultrasonic_mm[i];
    if (std::abs(sonars.mounts[i].yaw_rad) < 0.3 && mm != serial::kNoEcho) nearest = std::min(nearest, mm * 1e-3);
  }
  return nearest;
}

}  // namespace inspect::robot
