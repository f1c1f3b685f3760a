#include "sim/ultrasonic_model.hpp"

#include <algorithm>
#include <cmath>

#include "shared/serial/messages.hpp"

namespace inspect::sim {

UltrasonicModel::UltrasonicModel(const config::UltrasonicConfig& cfg, uint64_t seed) : cfg_(cfg), rng_(seed) {}

std::optional<double> UltrasonicModel::trueRange(const World& world, const control::Pose2& pose, int index,
                                                 std::span<const Circle> people) const {
  const control::Pose2 sensor = config::mountPose(pose, cfg_.mounts.at(static_cast<std::size_t>(index)));
  const Vec2 origin{sensor.x_m, sensor.y_m};
  const double axis = sensor.theta_rad;
  std::optional<double> best;
  for (int k = 0; k < kRaysPerBeam; ++k) {
    const double frac = static_cast<double>(k) / (kRaysPerBeam - 1) - 0.5;  // -0.5 .. 0.5
    const double yaw = axis + frac * cfg_.beam_width_rad;
    const auto hit = castRay(world, origin, yaw, cfg_.max_range_m);
    if (hit && (!best || *hit < *best)) best = hit;
    const Vec2 dir{std::cos(yaw), std::sin(yaw)};
    for (const auto& c : people) {
      const auto t = geometry::rayCircle(origin, dir, c);
      if (t && *t <= cfg_.max_range_m && (!best || *t < *best)) best = t;
    }
  }
  if (best) best = std::max(*best, cfg_.min_range_m);
  return best;
}

uint16_t UltrasonicModel::measureMm(const World& world, const control::Pose2& pose, int index,
                                    std::span<const Circle> people) {
  const auto r = trueRange(world, pose, index, people);
  if (!r) return serial::kNoEcho;
  std::uniform_real_distribution<double> noise(-cfg_.noise_m, cfg_.noise_m);
  const double noisy_m = std::clamp(*r + noise(rng_), cfg_.min_range_m, cfg_.max_range_m);
  // kNoEcho is reserved; 65.534 m is far beyond any configurable max range.
  return static_cast<uint16_t>(std::min(std::lround(noisy_m * 1000.0), 0xFFFEL));
}

std::array<uint16_t, 4> UltrasonicModel::measureAllMm(const World& world, const control::Pose2& pose,
                                                      std::span<const Circle> people) {
  std::array<uint16_t, 4> out{};
  for (int i = 0; i < 4; ++i) out[static_cast<std::size_t>(i)] = measureMm(world, pose, i, people);
  return out;
}

}  // namespace inspect::sim
