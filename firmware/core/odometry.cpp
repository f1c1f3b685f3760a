#include "firmware/core/odometry.hpp"

#include <cmath>

namespace inspect::firmware {

namespace {
constexpr double kPi = 3.14159265358979;
}

Odometry::Odometry(const McuSettings& s)
    : m_per_count_(2.0 * kPi * static_cast<double>(s.wheel_radius_m) / s.encoder_counts_per_rev),
      track_m_(static_cast<double>(s.track_m)) {}

void Odometry::update(int64_t left_counts, int64_t right_counts) {
  const std::array<int64_t, 2> now{left_counts, right_counts};
  // Everything from the totals, so nothing accumulates and any rate will do:
  // each wheel's travel in 0.1 mm (the frame's int32 wraps as the protocol
  // says), and the heading, linear in the travel difference.
  for (std::size_t i = 0; i < 2; ++i)
    disp_[i] = static_cast<int32_t>(static_cast<uint32_t>(std::llround(static_cast<double>(now[i]) * m_per_count_ * 1e4)));
  const double turned = static_cast<double>(now[1] - now[0]) * m_per_count_ / track_m_;
  heading_rad_ = static_cast<float>(std::remainder(turned, 2 * kPi));  // [-pi, pi]
}

int16_t Odometry::heading0p1mrad() const {
  const long v = std::lround(static_cast<double>(heading_rad_) * 1e4);
  return static_cast<int16_t>(v > 31416 ? 31416 : v < -31416 ? -31416 : v);
}

}  // namespace inspect::firmware
