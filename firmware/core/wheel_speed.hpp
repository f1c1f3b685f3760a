#pragma once
// One hub motor's speed loop, run every control period (1 ms): the speed from
// the encoder's counts over the last 20 ms; the set-point clamped to the
// wheel-speed limit; a feed-forward of it to a PWM duty in [-1, 1], and a PI
// that holds the wheel to the response the Pi's controllers are tuned on (a
// reference model: first order, robot.yaml's motor.time_constant_s), with
// anti-windup: the integral is held while the duty is saturated in the
// direction the error pushes.
//
// Why a reference model and not the PI on the set-point itself: the Pi's
// tracking controllers (fuzzy-PID, paper Eqs 10-15) close their own loop on
// the wheel speeds the frames report, with gains tuned on the robot's
// response. A PI that made the wheel answer in 30 ms instead of 0.2 s gave
// them another plant: through the firmware the circle's tracking oscillated
// at 7 Hz with commands swinging +-5 rad/s (docs/firmware.md). With the model
// the wheel answers as robot.yaml says whatever the load, the battery or the
// motor, and the PI only takes out what differs from it. No slew limit of its
// own for the same reason: the model's first order is the robot's
// acceleration (the Pi slews its own modes' set-points, not its tracking).
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
  /// enabled (false: brake, integral cleared; with a zero set-point: no drive, the wheel runs down)
  /// and the encoder counter. Returns the duty.
  float step(float setpoint_rad_s, bool enabled, uint16_t encoder_counter);

  /// The wheel's speed now, as the sensor frames report it: the reference
  /// model's speed plus the wheel's measured departure from it (the encoder's
  /// 20 ms window against the model's over the same window). The model has no
  /// lag and no quantisation; the departure (load, a stalled wheel, a weaker
  /// motor) is measured. The window's mean alone is 10 ms late, and that lag
  /// on the frames made the Pi's fuzzy-PID wheel loop oscillate
  /// (docs/firmware.md): its command variation 5 times the emulator's.
  float speedRadS() const { return estimate_rad_s_; }
  /// The encoder's own speed over the window (10 ms late on average).
  float measuredRadS() const { return speed_rad_s_; }
  float duty() const { return duty_; }
  /// The set-point after the clamp (0 when disabled).
  float appliedSetpoint() const { return target_; }
  /// The reference model's speed the PI holds the wheel to.
  float modelSpeed() const { return model_; }
  const EncoderTracker& encoder() const { return enc_; }

 private:
  const McuSettings& s_;
  float period_s_;
  float rad_per_count_;
  EncoderTracker enc_;
  float model_alpha_;      // the reference model's step per period, 1 - exp(-period / tau)
  float target_ = 0.0f;
  float model_ = 0.0f;     // the reference model's speed: where the wheel should be now
  // The model's speeds over the estimate's window: the PI compares like with
  // like (an average over the same 20 ms is 10 ms late on a ramp: 0.1 rad/s at 10 rad/s^2).
  std::array<float, EncoderTracker::kWindow> model_history_{};
  int model_head_ = 0;
  float modelWindowMean(int periods) const;
  float integral_ = 0.0f;  // duty
  float speed_rad_s_ = 0.0f;
  float estimate_rad_s_ = 0.0f;
  float duty_ = 0.0f;
};

}  // namespace inspect::firmware
