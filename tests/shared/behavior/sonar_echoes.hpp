#pragma once
// Synthetic sonar echoes for the behavior tests: each sensor's nearest hit of
// 7 rays across its cone against circles (people) and segments (walls), with
// optional uniform noise, as sim/ultrasonic_model does.
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "shared/behavior/human_tracker.hpp"

namespace inspect::test {

struct Circle {
  double x, y, r;
};

// Echo of each sensor: nearest hit of 7 rays across its cone against circles and segments (+- noise).
inline std::array<double, 4> echoes(const config::UltrasonicConfig& u, const control::Pose2& pose,
                             const std::vector<Circle>& people, const std::vector<geometry::Segment>& walls,
                             std::mt19937* rng = nullptr) {
  std::array<double, 4> out{};
  std::uniform_real_distribution<double> noise(-u.noise_m, u.noise_m);
  for (int i = 0; i < 4; ++i) {
    const control::Pose2 sensor = config::mountPose(pose, u.mounts[static_cast<std::size_t>(i)]);
    const double ox = sensor.x_m, oy = sensor.y_m;
    double best = u.max_range_m;
    for (int ray = -3; ray <= 3; ++ray) {
    const double yaw = sensor.theta_rad + ray * u.beam_width_rad / 6.0, dx = std::cos(yaw), dy = std::sin(yaw);
    for (const auto& p : people) {
      const double fx = ox - p.x, fy = oy - p.y;
      const double b = fx * dx + fy * dy, cc = fx * fx + fy * fy - p.r * p.r, disc = b * b - cc;
      if (disc < 0) continue;
      const double t = -b - std::sqrt(disc);
      if (t > 0) best = std::min(best, t);
    }
    for (const auto& w : walls) {
      const double ex = w.b.x - w.a.x, ey = w.b.y - w.a.y, den = dx * ey - dy * ex;
      if (std::abs(den) < 1e-12) continue;
      const double t = ((w.a.x - ox) * ey - (w.a.y - oy) * ex) / den;
      const double v = ((w.a.x - ox) * dy - (w.a.y - oy) * dx) / den;
      if (t > 0 && v >= 0 && v <= 1) best = std::min(best, t);
    }
    }
    out[static_cast<std::size_t>(i)] = best < u.max_range_m ? best + (rng ? noise(*rng) : 0.0) : -1.0;
  }
  return out;
}

}  // namespace inspect::test
