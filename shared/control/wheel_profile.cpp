#include "shared/control/wheel_profile.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace inspect::control {

const char* toString(WheelProfileSegment::Kind k) {
  switch (k) {
    case WheelProfileSegment::Kind::kHold: return "hold";
    case WheelProfileSegment::Kind::kStep: return "step";
    case WheelProfileSegment::Kind::kChirp: return "chirp";
  }
  return "?";
}

WheelProfile::WheelProfile(std::vector<WheelProfileSegment> segments, double max_wheel_rad_s)
    : segs_(std::move(segments)) {
  if (segs_.empty()) throw std::invalid_argument("a wheel profile needs at least one segment");
  for (std::size_t i = 0; i < segs_.size(); ++i) {
    const auto& s = segs_[i];
    const std::string where = "segment " + std::to_string(i + 1) + " (" + toString(s.kind) + "): ";
    if (!std::isfinite(s.duration_s) || s.duration_s <= 0.0 || s.duration_s > 600.0)
      throw std::invalid_argument(where + "duration_s must be in (0, 600]");
    for (double v : {s.left_rad_s, s.right_rad_s})
      if (!std::isfinite(v) || std::abs(v) > max_wheel_rad_s)
        throw std::invalid_argument(where + "wheel speeds must be finite and within +-" +
                                    std::to_string(max_wheel_rad_s) + " rad/s");
    if (s.kind == WheelProfileSegment::Kind::kChirp)
      for (double f : {s.f0_hz, s.f1_hz})
        if (!std::isfinite(f) || f <= 0.0 || f > 20.0)
          throw std::invalid_argument(where + "chirp frequencies must be in (0, 20] Hz");
    start_s_.push_back(duration_s_);
    duration_s_ += s.duration_s;
  }
}

WheelSpeeds WheelProfile::at(double t_s) const {
  if (!(t_s >= 0.0) || t_s >= duration_s_) return {};
  const std::size_t i =
      static_cast<std::size_t>(std::upper_bound(start_s_.begin(), start_s_.end(), t_s) - start_s_.begin()) - 1;
  const auto& s = segs_[i];
  const double tau = t_s - start_s_[i];
  switch (s.kind) {
    case WheelProfileSegment::Kind::kHold: return {};
    case WheelProfileSegment::Kind::kStep: return {s.left_rad_s, s.right_rad_s};
    case WheelProfileSegment::Kind::kChirp: {
      // Linear sweep: phase = 2 pi (f0 tau + (f1 - f0) tau^2 / (2 T)).
      const double phase = 2.0 * std::numbers::pi * (s.f0_hz * tau + (s.f1_hz - s.f0_hz) * tau * tau / (2.0 * s.duration_s));
      const double k = std::sin(phase);
      return {s.left_rad_s * k, s.right_rad_s * k};
    }
  }
  return {};
}

WheelProfile WheelProfile::standardIdentification(double a, double max_wheel_rad_s) {
  using K = WheelProfileSegment::Kind;
  if (!(max_wheel_rad_s >= 0.1) || !std::isfinite(a))
    throw std::invalid_argument("identification profile: the wheel limit must be at least 0.1 rad/s");
  a = std::clamp(std::abs(a), 0.1, max_wheel_rad_s);
  const double h = a / 2.0;
  std::vector<WheelProfileSegment> s = {
      {K::kHold, 1.0},
      // Spin-in-place steps (left back, right forward and the reverse), two levels.
      {K::kStep, 2.0, -h, h},
      {K::kHold, 1.5},
      {K::kStep, 2.0, -a, a},
      {K::kHold, 1.5},
      {K::kStep, 2.0, a, -a},
      {K::kHold, 1.5},
      {K::kStep, 2.0, h, -h},
      {K::kHold, 1.5},
      // Spin-in-place chirps, 0.1 to 3 Hz.
      {K::kChirp, 12.0, -h, h, 0.1, 3.0},
      {K::kHold, 1.0},
      // Forward and back by the same distance (0.5 s each at +-h).
      {K::kStep, 1.0, h, h},
      {K::kHold, 1.5},
      {K::kStep, 1.0, -h, -h},
      {K::kHold, 1.5},
  };
  return WheelProfile(std::move(s), max_wheel_rad_s);
}

}  // namespace inspect::control
