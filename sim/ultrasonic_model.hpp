#pragma once
// The four ultrasonic range sensors: a fan of rays across each beam cone
// against the world's walls and obstacles and the people in it, range limits
// and uniform noise.
#include <array>
#include <cstdint>
#include <optional>
#include <random>
#include <span>

#include "shared/config/robot_config.hpp"
#include "shared/control/diff_drive.hpp"
#include "shared/geometry/circle.hpp"
#include "sim/world_names.hpp"

namespace inspect::sim {

/// Ray-cast ultrasonic sensors with seeded noise.
class UltrasonicModel {
 public:
  /// Rays cast across each beam cone (edges included); the nearest hit counts.
  static constexpr int kRaysPerBeam = 7;

  UltrasonicModel(const config::UltrasonicConfig& cfg, uint64_t seed);

  /// Noise-free range of sensor `index` in metres (min_range_m when closer), or
  /// nullopt when nothing lies within max_range_m. `people` are solid circles.
  std::optional<double> trueRange(const World& world, const control::Pose2& pose, int index,
                                  std::span<const Circle> people = {}) const;
  /// One noisy measurement in millimetres as sent on the wire (serial::kNoEcho = no echo).
  uint16_t measureMm(const World& world, const control::Pose2& pose, int index, std::span<const Circle> people = {});
  /// All four sensors, in the wire order (front-left, front-right, left, right).
  std::array<uint16_t, 4> measureAllMm(const World& world, const control::Pose2& pose,
                                       std::span<const Circle> people = {});

 private:
  config::UltrasonicConfig cfg_;
  std::mt19937_64 rng_;
};

}  // namespace inspect::sim
