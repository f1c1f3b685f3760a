#include "firmware/core/wheel_speed.hpp"

#include <algorithm>

namespace inspect::firmware {

namespace {
constexpr float kTwoPi = 6.28318530718f;
}

void EncoderTracker::update(uint16_t counter) {
  if (started_) total_ += static_cast<int16_t>(static_cast<uint16_t>(counter - last_));  // wrapping difference
  started_ = true;
  last_ = counter;
  head_ = (head_ + 1) % static_cast<int>(history_.size());
  history_[static_cast<std::size_t>(head_)] = total_;
  if (filled_ < kWindow) ++filled_;
}

int32_t EncoderTracker::windowCounts() const {
  const int n = static_cast<int>(history_.size());
  const int oldest = (head_ - filled_ + n) % n;
  return static_cast<int32_t>(total_ - history_[static_cast<std::size_t>(oldest)]);
}

WheelSpeedLoop::WheelSpeedLoop(const McuSettings& s, float period_s)
    : s_(s), period_s_(period_s), rad_per_count_(kTwoPi / static_cast<float>(s.encoder_counts_per_rev)) {}

float WheelSpeedLoop::step(float setpoint_rad_s, bool enabled, uint16_t encoder_counter) {
  enc_.update(encoder_counter);
  const int periods = enc_.windowPeriods();
  speed_rad_s_ = periods > 0 ? static_cast<float>(enc_.windowCounts()) * rad_per_count_ /
                                   (static_cast<float>(periods) * period_s_)
                             : 0.0f;
  const float target = enabled ? std::clamp(setpoint_rad_s, -s_.max_wheel_speed_rad_s, s_.max_wheel_speed_rad_s) : 0.0f;
  const float max_step = s_.max_wheel_accel_rad_s2 * period_s_;
  slewed_ += std::clamp(target - slewed_, -max_step, max_step);
  if (!enabled || (target == 0.0f && slewed_ == 0.0f)) {
    // Brake to standstill, or stopped on purpose (the set-point and its ramp
    // at zero): no drive, nothing remembered. The integral would otherwise
    // hold the duty that was driving, and the wheel would creep on it after
    // the stop until it bled away (seen in the loop: -0.1 rad/s for a second).
    slewed_ = 0.0f;
    integral_ = 0.0f;
    duty_ = 0.0f;
    return duty_;
  }
  const float error = slewed_ - speed_rad_s_;
  const float unsaturated = s_.speed_ff * slewed_ + s_.speed_kp * error + integral_;
  duty_ = std::clamp(unsaturated, -1.0f, 1.0f);
  // Anti-windup (conditional integration): the integral grows only while the
  // duty is not saturated, or when the error pulls it back out of saturation.
  const bool saturated = duty_ != unsaturated;
  if (!saturated || (error > 0) != (unsaturated > 0))
    integral_ = std::clamp(integral_ + s_.speed_ki * error * period_s_, -1.0f, 1.0f);
  return duty_;
}

}  // namespace inspect::firmware
