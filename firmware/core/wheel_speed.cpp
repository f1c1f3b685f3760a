#include "firmware/core/wheel_speed.hpp"

#include <algorithm>
#include <cmath>

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
    : s_(s),
      period_s_(period_s),
      rad_per_count_(kTwoPi / static_cast<float>(s.encoder_counts_per_rev)),
      model_alpha_(s.response_tau_s > 0.0f ? 1.0f - std::exp(-period_s / s.response_tau_s) : 1.0f) {}

float WheelSpeedLoop::modelWindowMean(int periods) const {
  if (periods <= 0) return model_;
  float sum = 0.0f;
  for (int k = 0; k < periods; ++k)
    sum += model_history_[static_cast<std::size_t>((model_head_ - k + EncoderTracker::kWindow) % EncoderTracker::kWindow)];
  return sum / static_cast<float>(periods);
}

float WheelSpeedLoop::step(float setpoint_rad_s, bool enabled, uint16_t encoder_counter) {
  enc_.update(encoder_counter);
  const int periods = enc_.windowPeriods();
  speed_rad_s_ = periods > 0 ? static_cast<float>(enc_.windowCounts()) * rad_per_count_ /
                                   (static_cast<float>(periods) * period_s_)
                             : 0.0f;
  target_ = enabled ? std::clamp(setpoint_rad_s, -s_.max_wheel_speed_rad_s, s_.max_wheel_speed_rad_s) : 0.0f;
  if (!enabled) {
    // Braked: nothing remembered; a restart follows on from the wheel as it is.
    model_ = speed_rad_s_;
    model_history_.fill(model_);
    estimate_rad_s_ = speed_rad_s_;
    integral_ = 0.0f;
    duty_ = 0.0f;
    return duty_;
  }
  // The reference model: the set-point through the first order the robot's
  // response is (a motor whose own lag is that makes it from the feed-forward
  // alone; the PI makes up any difference).
  model_ += (target_ - model_) * model_alpha_;
  model_head_ = (model_head_ + 1) % EncoderTracker::kWindow;
  model_history_[static_cast<std::size_t>(model_head_)] = model_;
  const float error = modelWindowMean(periods) - speed_rad_s_;
  estimate_rad_s_ = model_ - error;
  if (target_ == 0.0f) {
    // Stopped on purpose: no drive, and the wheel runs down as the model
    // does. The integral would otherwise hold the duty that was driving, and
    // the wheel would creep on it after the stop until it bled away (seen in
    // the loop: -0.1 rad/s for a second).
    integral_ = 0.0f;
    duty_ = 0.0f;
    return duty_;
  }
  const float unsaturated = s_.speed_ff * target_ + s_.speed_kp * error + integral_;
  duty_ = std::clamp(unsaturated, -1.0f, 1.0f);
  // Anti-windup (conditional integration): the integral grows only while the
  // duty is not saturated, or when the error pulls it back out of saturation.
  const bool saturated = duty_ != unsaturated;
  if (!saturated || (error > 0) != (unsaturated > 0))
    integral_ = std::clamp(integral_ + s_.speed_ki * error * period_s_, -1.0f, 1.0f);
  return duty_;
}

}  // namespace inspect::firmware
