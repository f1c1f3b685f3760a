#include "firmware/core/ptz_servo.hpp"

#include <algorithm>
#include <cmath>

namespace inspect::firmware {

void PtzServo::setTarget(int16_t pan, int16_t tilt, bool home) {
  target_ = home ? std::array<float, 2>{} : std::array<float, 2>{pan * 1e-4f, tilt * 1e-4f};
}

void PtzServo::step() {
  const float max_step = s_.ptz_slew_rad_s * period_s_;
  for (std::size_t i = 0; i < 2; ++i) angle_[i] += std::clamp(target_[i] - angle_[i], -max_step, max_step);
}

std::array<uint16_t, 2> PtzServo::pulsesUs() const {
  std::array<uint16_t, 2> out{};
  for (std::size_t i = 0; i < 2; ++i) {
    const float us = std::round(kCentreUs + s_.servo_us_per_rad * angle_[i]);
    out[i] = static_cast<uint16_t>(std::clamp(us, static_cast<float>(kMinUs), static_cast<float>(kMaxUs)));
  }
  return out;
}

}  // namespace inspect::firmware
