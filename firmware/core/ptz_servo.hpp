#pragma once
// The camera mount's two hobby servos (pan, tilt): a PtzCommand's set-point
// (0.1 mrad; HOME = 0/0) moved towards at ptz_slew_rad_s, as a pulse width
// of 1500 us +- servo_us_per_rad x angle, within 500-2500 us.
#include <array>
#include <cstdint>

#include "firmware/core/mcu_settings.hpp"

namespace inspect::firmware {

class PtzServo {
 public:
  static constexpr uint16_t kCentreUs = 1500, kMinUs = 500, kMaxUs = 2500;
  PtzServo(const McuSettings& s, float period_s) : s_(s), period_s_(period_s) {}
  void setTarget(int16_t pan_0p1mrad, int16_t tilt_0p1mrad, bool home);
  /// One period: the angles move towards the target.
  void step();
  std::array<float, 2> anglesRad() const { return angle_; }
  /// Where the last command asked it to go, pan and tilt, rad.
  std::array<float, 2> targetRad() const { return target_; }
  /// The pulse widths now, pan and tilt, us.
  std::array<uint16_t, 2> pulsesUs() const;

 private:
  const McuSettings& s_;
  float period_s_;
  std::array<float, 2> target_{};
  std::array<float, 2> angle_{};
};

}  // namespace inspect::firmware
