// Ultrasonic and grayscale models against simple worlds.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "shared/config/robot_config.hpp"
#include "shared/serial/messages.hpp"
#include "sim/grayscale_model.hpp"
#include "sim/ultrasonic_model.hpp"
#include "tests/sim/world_text.hpp"

using namespace inspect;
using namespace inspect::sim;

namespace {

using inspect::test::worldOf;

}  // namespace

TEST(Ultrasonic, WallAtOneMetreReadsWithinPaperAccuracy) {
  const config::UltrasonicConfig cfg;
  // Front-left sensor at (0.30, 0.12) facing +x; wall 1.0 m ahead of it.
  const World w = worldOf("walls:\n  - {from_m: [1.30, -5], to_m: [1.30, 5]}\n", "w.yaml");
  UltrasonicModel us(cfg, 42);
  const control::Pose2 pose{};
  ASSERT_TRUE(us.trueRange(w, pose, serial::kFrontLeft));
  EXPECT_NEAR(*us.trueRange(w, pose, serial::kFrontLeft), 1.0, 1e-9);
  double sum = 0.0;
  int lo = 0, hi = 0;
  constexpr int kSamples = 5000;
  for (int i = 0; i < kSamples; ++i) {
    const uint16_t mm = us.measureMm(w, pose, serial::kFrontLeft);
    ASSERT_NE(mm, serial::kNoEcho);
    ASSERT_NEAR(mm / 1000.0, 1.0, 0.03 + 0.0005);
    sum += mm;
    lo += mm < 990;
    hi += mm > 1010;
  }
  EXPECT_NEAR(sum / kSamples / 1000.0, 1.0, 0.002);
  EXPECT_GT(lo, kSamples / 5);  // the noise really spreads over +-0.03 m
  EXPECT_GT(hi, kSamples / 5);
}

TEST(Ultrasonic, SameSeedSameReadings) {
  const config::UltrasonicConfig cfg;
  const World w = worldOf("walls:\n  - {from_m: [2, -5], to_m: [2, 5]}\n", "w.yaml");
  UltrasonicModel a(cfg, 7), b(cfg, 7), c(cfg, 8);
  bool differs = false;
  for (int i = 0; i < 20; ++i) {
    const auto ra = a.measureAllMm(w, {});
    EXPECT_EQ(ra, b.measureAllMm(w, {}));
    differs |= ra != c.measureAllMm(w, {});
  }
  EXPECT_TRUE(differs);
}

TEST(Ultrasonic, NoEchoBeyondMaxRangeAndClampedBelowMin) {
  config::UltrasonicConfig cfg;
  cfg.noise_m = 0.0;
  UltrasonicModel us(cfg, 1);
  const World far = worldOf("walls:\n  - {from_m: [5.0, -0.1], to_m: [5.0, 0.1]}\n", "w.yaml");
  EXPECT_EQ(us.measureMm(far, {}, serial::kFrontLeft), serial::kNoEcho);
  const World near = worldOf("walls:\n  - {from_m: [0.31, -1], to_m: [0.31, 1]}\n", "w.yaml");
  EXPECT_EQ(us.measureMm(near, {}, serial::kFrontLeft), 20);  // min_range_m
}

TEST(Ultrasonic, BeamConeSeesObliqueTargets) {
  config::UltrasonicConfig cfg;
  cfg.noise_m = 0.0;
  UltrasonicModel us(cfg, 1);
  // A post 2 m ahead, 0.4 m to the left of the front-left sensor axis: inside
  // the 30 degree cone (atan(0.4/2) = 11 deg) but off the axis.
  const World w = worldOf("obstacles:\n  - {vertices_m: [2.3,0.45, 2.35,0.45, 2.35,0.6, 2.3,0.6]}\n", "w.yaml");
  const auto r = us.trueRange(w, {}, serial::kFrontLeft);
  ASSERT_TRUE(r);
  EXPECT_GT(*r, 2.0);
  EXPECT_LT(*r, 2.1);
  cfg.beam_width_rad = 0.0;
  UltrasonicModel pencil(cfg, 1);
  EXPECT_FALSE(pencil.trueRange(w, {}, serial::kFrontLeft));
}

TEST(Ultrasonic, SideSensorsFollowTheRobotHeading) {
  config::UltrasonicConfig cfg;
  cfg.noise_m = 0.0;
  UltrasonicModel us(cfg, 1);
  // Wall along y = 2; robot at the origin facing +x: the left sensor (0, 0.25,
  // +90 deg) sees it at 1.75 m; turned to face -x, the right sensor does.
  const World w = worldOf("walls:\n  - {from_m: [-10, 2], to_m: [10, 2]}\n", "w.yaml");
  EXPECT_EQ(us.measureMm(w, {}, serial::kLeft), 1750);
  EXPECT_EQ(us.measureMm(w, {}, serial::kRight), serial::kNoEcho);
  EXPECT_EQ(us.measureMm(w, {0, 0, std::numbers::pi}, serial::kRight), 1750);
}

TEST(Grayscale, ChannelsAcrossTheFront) {
  EXPECT_DOUBLE_EQ(GrayscaleModel::spotInRobot(0).y, 0.07);
  EXPECT_DOUBLE_EQ(GrayscaleModel::spotInRobot(7).y, -0.07);
  EXPECT_DOUBLE_EQ(GrayscaleModel::spotInRobot(3).x, GrayscaleModel::kRowX_m);
  // A 2.5 cm line along x under the robot's centre: the middle channels see it.
  const World w = worldOf("floor_lines:\n  - {from_m: [-1, 0], to_m: [1, 0], width_m: 0.025}\n", "w.yaml");
  EXPECT_EQ(GrayscaleModel::read(w, {}), 0b00011000);
  // Robot 5 cm to the right of the line (-y): only channel 1 (left side) sees it.
  EXPECT_EQ(GrayscaleModel::read(w, {0, -0.05, 0}), 0b00000010);
  // Facing along +y across the line: no channel on it unless the row crosses it.
  EXPECT_EQ(GrayscaleModel::read(w, {0, 0, std::numbers::pi / 2}), 0);
  EXPECT_EQ(GrayscaleModel::read(w, {0, -0.25, std::numbers::pi / 2}), 0xFF);
}
