// Obstacle perception from the four sonars: reading -> point (mount poses,
// wall-normal placement), odometry frame, the fixed ring-buffer memory, and
// the summary (avoid vector, nearest point, goal corridor, side views).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "shared/config/robot_config.hpp"
#include "shared/navigation/obstacle_memory.hpp"
#include "shared/serial/messages.hpp"
#include "tests/shared/navigation/nav_test_values.hpp"

using namespace inspect;
using namespace inspect::navigation;
using inspect::test::kNaN;
using inspect::test::kPi;
using inspect::test::kSonar;

namespace {


struct PointCase {
  int mount;
  double range_m;
  std::optional<double> normal_rad;
  bool valid;
  double x_m, y_m;  // expected robot-frame point
};

class SonarPointTable : public ::testing::TestWithParam<PointCase> {};

TEST_P(SonarPointTable, PointFromMountAndRange) {
  const PointCase& c = GetParam();
  const auto p = sonarPoint(kSonar.mounts[static_cast<std::size_t>(c.mount)], kSonar, c.range_m, 2.0, c.normal_rad);
  ASSERT_EQ(p.has_value(), c.valid);
  if (!c.valid) return;
  EXPECT_NEAR(p->x, c.x_m, 1e-9);
  EXPECT_NEAR(p->y, c.y_m, 1e-9);
}

const double kHalfBeam = kSonar.beam_width_rad / 2.0;

INSTANTIATE_TEST_SUITE_P(
    Mounts, SonarPointTable,
    ::testing::Values(
        // On the beam axis, from the config's mounts: FL (0.30, 0.12, 0), FR (0.30, -0.12, 0),
        // L (0, 0.25, +pi/2), R (0, -0.25, -pi/2).
        PointCase{0, 1.0, std::nullopt, true, 1.30, 0.12}, PointCase{1, 1.0, std::nullopt, true, 1.30, -0.12},
        PointCase{2, 1.0, std::nullopt, true, 0.0, 1.25}, PointCase{3, 0.5, std::nullopt, true, 0.0, -0.75},
        // Out of range or no echo.
        PointCase{0, kNaN, std::nullopt, false, 0, 0}, PointCase{0, 0.01, std::nullopt, false, 0, 0},
        PointCase{0, 4.6, std::nullopt, false, 0, 0}, PointCase{0, 2.5, std::nullopt, false, 0, 0},
        PointCase{0, 0.02, std::nullopt, true, 0.32, 0.12},
        // A flat wall's normal inside the cone: the echo point lies along it.
        PointCase{2, 1.0, kPi / 2 + 0.1, true, std::cos(kPi / 2 + 0.1), 0.25 + std::sin(kPi / 2 + 0.1)},
        // Outside the cone: on the cone's edge nearest to it.
        PointCase{2, 1.0, kPi / 2 - 1.0, true, std::cos(kPi / 2 - kHalfBeam), 0.25 + std::sin(kPi / 2 - kHalfBeam)},
        PointCase{3, 1.0, -kPi / 2 - 1.0, true, std::cos(-kPi / 2 - kHalfBeam),
                  -0.25 + std::sin(-kPi / 2 - kHalfBeam)}));

TEST(Sonar, RangesFromWireMillimetres) {
  const SonarRanges r = rangesFromMm({1234, serial::kNoEcho, 20, 4500});
  EXPECT_DOUBLE_EQ(r[0], 1.234);
  EXPECT_TRUE(std::isnan(r[1]));
  EXPECT_DOUBLE_EQ(r[2], 0.020);
  EXPECT_DOUBLE_EQ(r[3], 4.5);
}

TEST(Sonar, RobotToOdometryFrame) {
  const Vec2 p = toOdometryFrame({1.0, 2.0, kPi / 2}, {1.0, 0.5});
  EXPECT_NEAR(p.x, 0.5, 1e-12);
  EXPECT_NEAR(p.y, 3.0, 1e-12);
}

TEST(Memory, ExpiresByAgeOldestFirst) {
  ObstacleMemory m;
  for (int i = 0; i < 10; ++i) m.add({static_cast<double>(i), 0.0}, 0.1 * i);
  m.expire(1.0, 0.45);  // keeps t >= 0.55: i = 6..9
  ASSERT_EQ(m.size(), 4u);
  EXPECT_DOUBLE_EQ(m.point(0).x, 6.0);
  EXPECT_DOUBLE_EQ(m.point(3).x, 9.0);
  m.clear();
  EXPECT_EQ(m.size(), 0u);
}

TEST(Memory, FullBufferOverwritesOldestWithoutGrowing) {
  ObstacleMemory m;
  const std::size_t n = ObstacleMemory::kCapacity + 10;
  for (std::size_t i = 0; i < n; ++i) m.add({static_cast<double>(i), 0.0}, 0.0);
  EXPECT_EQ(m.size(), ObstacleMemory::kCapacity);
  EXPECT_DOUBLE_EQ(m.point(0).x, 10.0);
  EXPECT_DOUBLE_EQ(m.point(ObstacleMemory::kCapacity - 1).x, static_cast<double>(n - 1));
}

TEST(Memory, IgnoresNonFinitePoints) {
  ObstacleMemory m;
  m.add({kNaN, 0.0}, 0.0);
  m.add({0.0, 0.0}, kNaN);
  EXPECT_EQ(m.size(), 0u);
}

TEST(Summary, EmptyMemoryMeansNoObstacle) {
  const ObstacleSummary s = summarise(ObstacleMemory{}, {0, 0, 0}, {5, 0}, 0.0, NavigationParams{});
  EXPECT_FALSE(s.any);
  EXPECT_TRUE(std::isinf(s.nearest_m));
  EXPECT_EQ(norm(s.avoid), 0.0);
  EXPECT_FALSE(s.goal_blocked);
}

TEST(Summary, PointAheadPushesBackAndBlocksTheGoal) {
  ObstacleMemory m;
  m.add({0.8, 0.0}, 0.0);
  const NavigationParams p;
  const ObstacleSummary s = summarise(m, {0, 0, 0}, {5, 0}, 0.0, p);
  EXPECT_NEAR(s.nearest_m, 0.8, 1e-12);
  EXPECT_NEAR(s.nearest_bearing_rad, 0.0, 1e-12);
  EXPECT_NEAR(angleOf(s.avoid), kPi, 1e-9);  // Eq 5.20: x - x_o points back
  EXPECT_TRUE(s.goal_blocked);
  // The same point seen with the goal to the side is out of the corridor.
  EXPECT_FALSE(summarise(m, {0, 0, 0}, {0, 5}, 0.0, p).goal_blocked);
  // A point beyond the goal is not in the way: the robot stops at the goal.
  EXPECT_FALSE(summarise(m, {0, 0, 0}, {0.5, 0}, 0.0, p).goal_blocked);
  EXPECT_TRUE(summarise(m, {0, 0, 0}, {0.5, 0}, 0.0, p).goal_near);
  EXPECT_FALSE(s.goal_near);
  // Beyond the caution distance it is remembered but does not push.
  ObstacleMemory far;
  far.add({1.6, 0.0}, 0.0);
  const ObstacleSummary f = summarise(far, {0, 0, 0}, {5, 0}, 0.0, p);
  EXPECT_TRUE(f.any);
  EXPECT_EQ(norm(f.avoid), 0.0);
  EXPECT_NEAR(angleOf(f.away_from_nearest), kPi, 1e-9);
}

TEST(Summary, CloserPointsWeighMore) {
  ObstacleMemory m;
  m.add({0.7, 0.0}, 0.0);  // ahead, near
  m.add({0.0, 1.2}, 0.0);  // left, far
  const ObstacleSummary s = summarise(m, {0, 0, 0}, {5, 0}, 0.0, NavigationParams{});
  const double a = angleOf(s.avoid);
  EXPECT_LT(a, -3.0 * kPi / 4.0);  // mostly away from the near point (back) ...
  EXPECT_GT(a, -kPi);              // ... and a little away from the far one (down)
}

TEST(Summary, WallOnTheLeftIsFittedAsALine) {
  // Points of a wall along y = 0.8 (as the left sonar leaves them while the
  // robot drives along it), with +-0.02 m of alternating noise.
  ObstacleMemory m;
  for (int i = 0; i <= 60; ++i) m.add({-0.6 + 0.01 * i, 0.8 + (i % 2 ? 0.02 : -0.02)}, 0.01 * i);
  const ObstacleSummary s = summarise(m, {0, 0, 0}, {5, 0}, 0.6, NavigationParams{});
  EXPECT_TRUE(s.left.line_fit);
  EXPECT_NEAR(s.left.distance_m, 0.8, 0.01);
  EXPECT_NEAR(angleOf(s.left.avoid), -kPi / 2, 0.02);
  // Behind-left points are not on the right side (only the front sector is shared).
  EXPECT_TRUE(std::isinf(s.right.nearest_m));
}

TEST(Summary, PassedEndOfAWallIsRoundedLikeACorner) {
  // The wall's points end at x = 0; the robot heads +x and is 0.6 m past the
  // last point (more than the 0.3 m lookahead), so x_o is the fitted
  // segment's end, 0.3 m beyond the last point.
  ObstacleMemory m;
  for (int i = 0; i <= 60; ++i) m.add({-0.6 + 0.01 * i, 0.8}, 0.0);
  const NavigationParams p;
  const ObstacleSummary s = summarise(m, {0.6, 0, 0}, {5, 0}, 0.0, p);
  ASSERT_TRUE(s.left.line_fit);
  const Vec2 xo{0.0 + p.follow_lookahead_m, 0.8};
  EXPECT_NEAR(s.left.distance_m, norm(Vec2{0.6, 0} - xo), 1e-6);
  EXPECT_GT(angleOf(s.left.avoid), -kPi / 2 + 0.1);  // away from the end, tilted forward: round it
}

}  // namespace
