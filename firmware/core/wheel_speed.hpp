#pragma once
// One hub motor's speed loop, run every control period (1 ms): the speed from
// the encoder's counts over the last 10 ms, a PI on it with feed-forward to a
// PWM duty in [-1, 1], the set-point clamped to the wheel-speed limit and
// slewed at the acceleration limit, and anti-windup: the integral is held
// while the duty is saturated in the direction the error pushes.
#include <array>
#include <cstdint>

#include "firmware/core/mcu_settings.hpp"

namespace inspect::firmware {

/// The encoder's counter (a timer in encoder mode, 16 bits, wrapping) turned
/// into a running total and a speed over a window of periods.
class EncoderTracker {
 public:
  static constexpr int kWindow = 20;  // periods of the speed estimate (20 ms at 1 kHz)

  /// The counter's value this period; the first call only takes its origin.
  void update(uint16_t counter);
  /// Counts since start (wraps only after 2^63 counts).
  int64_t total() const { return total_; }
  /// Counts over the last kWindow periods (fewer just after start).
  int32_t windowCounts() const;
  /// Periods the window holds (kWindow once full).
  int windowPeriods() const { return filled_; }

 private:
  bool started_ = false;
  uint16_t last_ = 0;
  int64_t total_ = 0;
  std::array<int64_t, kWindow + 1> history_{};  // totals of the last kWindow + 1 periods
  int head_ = 0;
  int filled_ = 0;
};

class WheelSpeedLoop {
 public:
  WheelSpeedLoop(const McuSettings& s, float period_s);

  /// One period: the new set-point (rad/s, clamped here), whether the motor is
  /// enabled (false: brake, integral cleared; so too once the set-point and its ramp are at zero)
  /// and the encoder counter. Returns the duty.
  float step(float setpoint_rad_s, bool enabled, uint16_t encoder_counter);

  float speedRadS() const { return speed_rad_s_; }
  float duty() const { return duty_; }
  /// The set-point after the clamp and the slew limit.
  float appliedSetpoint() const { return slewed_; }
  const EncoderTracker& encoder() const { return enc_; }

 private:
  const McuSettings& s_;
  float period_s_;
  float rad_per_count_;
  EncoderTracker enc_;
  float slewed_ = 0.0f;
  float integral_ = 0.0f;  // duty
  float speed_rad_s_ = 0.0f;
  float duty_ = 0.0f;
};

}  // namespace inspect::firmware
