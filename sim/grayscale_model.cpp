#include "sim/grayscale_model.hpp"

#include <cmath>

namespace inspect::sim {

Vec2 GrayscaleModel::spotInRobot(int channel) {
  return {kRowX_m, (0.5 * (kChannels - 1) - channel) * kSpacing_m};
}

uint8_t GrayscaleModel::read(const World& world, const control::Pose2& pose) {
  if (world.floor_lines.empty()) return 0;
  const double c = std::cos(pose.theta_rad);
  const double s = std::sin(pose.theta_rad);
  uint8_t bits = 0;
  for (int i = 0; i < kChannels; ++i) {
    const Vec2 p = spotInRobot(i);
    const Vec2 w{pose.x_m + c * p.x - s * p.y, pose.y_m + s * p.x + c * p.y};
    if (onFloorLine(world, w)) bits = static_cast<uint8_t>(bits | (1u << i));
  }
  return bits;
}

}  // namespace inspect::sim
