#pragma once
// Wheel travel and heading from the encoders' totals (docs/serial-protocol.md
// SensorFrame): each wheel's cumulative travel in 0.1 mm (int32, wrapping),
// and the heading from the difference of the wheels' travel since boot
// (Eq 1's differential drive: theta = (d_right - d_left) / track),
// counter-clockwise positive, wrapped to [-pi, pi], in 0.1 mrad. A pure
// function of the totals: computed when a frame is built, not every tick.
#include <array>
#include <cstdint>

#include "firmware/core/mcu_settings.hpp"

namespace inspect::firmware {

class Odometry {
 public:
  explicit Odometry(const McuSettings& s);
  /// The encoders' totals (counts since start, left and right).
  void update(int64_t left_counts, int64_t right_counts);
  std::array<int32_t, 2> displacement0p1mm() const { return disp_; }
  int16_t heading0p1mrad() const;
  float headingRad() const { return heading_rad_; }

 private:
  double m_per_count_;
  double track_m_;
  std::array<int32_t, 2> disp_{};
  float heading_rad_ = 0.0f;
};

}  // namespace inspect::firmware
