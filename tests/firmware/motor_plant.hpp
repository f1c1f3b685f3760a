#pragma once
// A hub motor for the firmware's host tests: first order, omega' = (K duty -
// omega) / tau (robot.yaml motor.time_constant_s; K = 1 / speed_ff, the
// no-load speed at full duty), with an encoder counting its turns as the
// timer in encoder mode does (16 bits, wrapping).
#include <cmath>
#include <cstdint>

#include "firmware/core/mcu_settings.hpp"

namespace inspect::firmware::test {

struct MotorPlant {
  explicit MotorPlant(const McuSettings& s, float tau_s = 0.2f)
      : gain(1.0f / s.speed_ff), tau(tau_s), counts_per_rad(s.encoder_counts_per_rev / 6.28318530718f) {}
  /// Advances dt with `duty` (brake: speed to 0 at once, as shorted windings nearly do).
  void step(float duty, bool brake, float dt) {
    if (brake) omega = 0.0f;
    else if (!stalled) omega += (gain * duty - omega) / tau * dt;
    if (stalled) omega = 0.0f;
    position_counts += static_cast<double>(omega) * dt * counts_per_rad;
  }
  uint16_t counter() const { return static_cast<uint16_t>(static_cast<int64_t>(std::floor(position_counts)) + offset); }
  float gain, tau, counts_per_rad;
  float omega = 0.0f;
  double position_counts = 0.0;
  int64_t offset = 65000;  // the timer's counter starts near its wrap
  bool stalled = false;    // held by hand: no motion whatever the duty
};

}  // namespace inspect::firmware::test
