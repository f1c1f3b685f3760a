#pragma once
// The 8-channel grayscale line sensor: a row of spots across the front of the
// chassis, each reading "line" when it lies over a floor line.
#include <cstdint>

#include "shared/control/diff_drive.hpp"
#include "sim/world_names.hpp"

namespace inspect::sim {

/// Grayscale line sensor geometry and readout (docs/simulator.md).
class GrayscaleModel {
 public:
  static constexpr int kChannels = 8;
  /// Forward offset of the sensor row from the axle midpoint.
  static constexpr double kRowX_m = 0.25;
  /// Lateral spacing of the spots; channel 0 is the leftmost (+y).
  static constexpr double kSpacing_m = 0.02;

  /// Position of channel i in the robot frame (x forward, y left).
  static Vec2 spotInRobot(int channel);
  /// Bit i set when channel i is over a floor line.
  static uint8_t read(const World& world, const control::Pose2& pose);
};

}  // namespace inspect::sim
