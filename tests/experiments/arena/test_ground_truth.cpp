// The arena's ground truth (experiments/arena/ground_truth): the pattern from
// relative heading and lateral offset, and what the sonars could see.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "experiments/arena/ground_truth.hpp"
#include "shared/world/world.hpp"

using namespace inspect;
using inspect::behavior::Pattern;
using inspect::arena::TruePerson;

namespace {
constexpr double kDeg = std::numbers::pi / 180.0;
/// A person at (x, y) walking at 1 m/s with heading `deg` (world frame).
TruePerson walker(double x, double y, double deg, double speed = 1.0) {
  return {{x, y}, {speed * std::cos(deg * kDeg), speed * std::sin(deg * kDeg)}, 0.25};
}
const control::Pose2 kRobot{0, 0, 0};  // at the origin facing +x
}  // namespace

TEST(GroundTruth, CrossingByRelativeHeading) {
  for (double deg : {31.0, 45.0, 90.0, 135.0, 149.0, -90.0, -45.0})
    EXPECT_EQ(arena::truePattern(kRobot, walker(3, 1, deg)), Pattern::kCrossing) << deg;
  // 30 and 150 degrees themselves belong to the same / opposite direction.
  EXPECT_EQ(arena::truePattern(kRobot, walker(3, 0, 30)), Pattern::kLeading);
  EXPECT_EQ(arena::truePattern(kRobot, walker(3, 0, 150)), Pattern::kConfronting);
}

TEST(GroundTruth, OnThePathOrBesideIt) {
  EXPECT_EQ(arena::truePattern(kRobot, walker(3, 0.3, 0)), Pattern::kLeading);
  EXPECT_EQ(arena::truePattern(kRobot, walker(3, 1.0, 0)), Pattern::kNone);  // walking alongside
  EXPECT_EQ(arena::truePattern(kRobot, walker(3, -0.5, 180)), Pattern::kConfronting);
  EXPECT_EQ(arena::truePattern(kRobot, walker(3, 1.2, 180)), Pattern::kEncountering);
  EXPECT_EQ(arena::truePattern(kRobot, walker(3, -1.9, 175)), Pattern::kEncountering);
  EXPECT_EQ(arena::truePattern(kRobot, walker(3, 2.5, 180)), Pattern::kNone);  // beyond max_lateral
}

TEST(GroundTruth, NobodyBehindStandingOrFar) {
  EXPECT_EQ(arena::truePattern(kRobot, walker(-1, 0, 0)), Pattern::kNone);
  EXPECT_EQ(arena::truePattern(kRobot, walker(2, 0, 180, 0.05)), Pattern::kNone);
  EXPECT_EQ(arena::truePattern(kRobot, walker(7, 0, 180)), Pattern::kNone);
}

TEST(GroundTruth, TheRobotsHeadingCounts) {
  // The robot faces +y: a person ahead on +y walking towards it confronts it.
  const control::Pose2 robot{0, 0, std::numbers::pi / 2};
  EXPECT_EQ(arena::truePattern(robot, walker(0, 3, -90)), Pattern::kConfronting);
  EXPECT_EQ(arena::truePattern(robot, walker(0, 3, 0)), Pattern::kCrossing);
  EXPECT_EQ(arena::truePattern(robot, walker(0, 3, 90)), Pattern::kLeading);
}

TEST(GroundTruth, ObservableInAConeWithNothingInBetween) {
  const config::UltrasonicConfig sonar;  // front sonars at (0.3, +-0.12) facing ahead, 30 degree cones, 4.5 m
  world::World empty;
  EXPECT_TRUE(arena::observable(kRobot, walker(2, 0, 180), sonar, empty));
  EXPECT_FALSE(arena::observable(kRobot, walker(6, 0, 180), sonar, empty));      // out of range
  EXPECT_FALSE(arena::observable(kRobot, walker(2, 1.6, 180), sonar, empty));    // between the front and side cones
  EXPECT_TRUE(arena::observable(kRobot, walker(0, 2, 0), sonar, empty));         // the left sonar
  world::World wall;
  wall.walls.push_back({{1.0, -2.0}, {1.0, 2.0}});
  EXPECT_FALSE(arena::observable(kRobot, walker(2, 0, 180), sonar, wall));  // behind a wall
}
