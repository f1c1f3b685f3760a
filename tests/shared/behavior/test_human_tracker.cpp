// Human tracking from the 4 ultrasonic sensors, with synthetic echoes.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <random>

#include "shared/behavior/human_tracker.hpp"
#include "tests/shared/behavior/sonar_echoes.hpp"

using namespace inspect;
using behavior::HumanTracker;
using test::Circle;
using test::echoes;

TEST(HumanTracker, CrossingPersonIsTrackedWithItsVelocity) {
  const config::UltrasonicConfig u;
  HumanTracker tr(u, {});
  std::mt19937 rng(3);
  const control::Pose2 robot{0, 0, 0};
  // A person 2.5 m ahead walking from left to right at 0.5 m/s.
  std::optional<behavior::HumanTrack> seen;
  for (int k = 0; k < 400; ++k) {
    const double t = k * 0.01;
    const Circle p{2.5, 1.0 - 0.5 * t, 0.25};
    tr.step(robot, echoes(u, robot, {p}, {}, &rng), t);
    if (k == 220) {  // the person is just right of the centre line, inside both front cones
      if (const auto* n = tr.nearest(robot)) seen = *n;
    }
  }
  // Two sonars see a crossing person only through their cones: the lateral
  // speed is observed weakly, but its sign and the range are right.
  ASSERT_TRUE(seen.has_value());
  EXPECT_LT(seen->x[3], -0.05) << "moving to the right";
  EXPECT_NEAR(seen->x[2], 0.0, 0.25) << "vx";
  EXPECT_NEAR(seen->x[0], 2.5 - 0.25, 0.25);
  EXPECT_GE(tr.counters().tracks_confirmed, 1u);
}

TEST(HumanTracker, AWallAheadIsNotAPerson) {
  const config::UltrasonicConfig u;
  HumanTracker tr(u, {});
  const control::Pose2 robot{0, 0, 0};
  const std::vector<geometry::Segment> wall = {{2.0, -3, 2.0, 3}};
  std::mt19937 rng(4);
  int person_ticks = 0;
  for (int k = 0; k < 500; ++k) {
    tr.step(robot, echoes(u, robot, {}, wall, &rng), k * 0.01);
    if (tr.nearest(robot)) ++person_ticks;
  }
  EXPECT_EQ(person_ticks, 0);
  EXPECT_GT(tr.counters().static_grid, 0u);
}

TEST(HumanTracker, KnownMapWallsAreDroppedWhileDriving) {
  const config::UltrasonicConfig u;
  const std::vector<geometry::Segment> walls = {{-1, 1.2, 20, 1.2}, {-1, -1.2, 20, -1.2}};
  HumanTracker tr(u, {}, walls);
  std::mt19937 rng(5);
  int person_ticks = 0;
  for (int k = 0; k < 600; ++k) {
    const control::Pose2 robot{0.005 * k, 0, 0};  // 0.5 m/s along an aisle
    tr.step(robot, echoes(u, robot, {}, walls, &rng), k * 0.01);
    if (tr.nearest(robot)) ++person_ticks;
  }
  EXPECT_EQ(person_ticks, 0);
  EXPECT_GT(tr.counters().static_map, 500u);
}

TEST(HumanTracker, SporadicFalseEchoesDoNotMakeAPerson) {
  const config::UltrasonicConfig u;
  HumanTracker tr(u, {});
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> r(0.3, 4.0);
  std::uniform_int_distribution<int> which(0, 3);
  const control::Pose2 robot{0, 0, 0};
  int person_ticks = 0;
  for (int k = 0; k < 1000; ++k) {
    std::array<double, 4> e = {-1, -1, -1, -1};
    if (k % 37 == 0) e[static_cast<std::size_t>(which(rng))] = r(rng);  // a stray echo now and then
    tr.step(robot, e, k * 0.01);
    if (tr.nearest(robot)) ++person_ticks;
  }
  EXPECT_EQ(person_ticks, 0);
  EXPECT_GT(tr.counters().tracks_unconfirmed_dropped, 10u);
}

TEST(HumanTracker, NonFiniteRangesAreIgnored) {
  const config::UltrasonicConfig u;
  HumanTracker tr(u, {});
  tr.step({0, 0, 0}, {std::nan(""), INFINITY, -1, 0}, 0.0);
  EXPECT_EQ(tr.counters().echoes, 0u);
}

TEST(HumanTracker, OncomingPersonHasItsClosingSpeed) {
  const config::UltrasonicConfig u;
  HumanTracker tr(u, {});
  std::mt19937 rng(8);
  const control::Pose2 robot{0, 0, 0};
  std::optional<behavior::HumanTrack> seen;
  for (int k = 0; k < 500; ++k) {
    const double t = k * 0.01;
    tr.step(robot, echoes(u, robot, {{4.0 - 0.5 * t, 0.1, 0.25}}, {}, &rng), t);
    if (k == 400) {
      if (const auto* n = tr.nearest(robot)) seen = *n;
    }
  }
  ASSERT_TRUE(seen.has_value());
  EXPECT_NEAR(seen->x[2], -0.5, 0.1);
  EXPECT_NEAR(seen->x[0], 4.0 - 0.5 * 4.0 - 0.25, 0.15);
}

// Without a map, a corridor's walls slide past the side sensors at the robot's
// speed (and reach the front cones' rims at a range that slides with it): the
// side traces are recognised as walls and remembered for the front sensors.
TEST(HumanTracker, CorridorWallsWithoutAMapAreNotPeople) {
  const config::UltrasonicConfig u;
  const std::vector<geometry::Segment> walls = {{-1, 1.2, 30, 1.2}, {-1, -1.2, 30, -1.2}};
  auto run = [&](bool wall_trace) {
    behavior::HumanTrackerParams p;
    p.wall_trace = wall_trace;
    HumanTracker tr(u, p);  // no map
    std::mt19937 rng(6);
    int person_ticks = 0;
    for (int k = 0; k < 2000; ++k) {  // 20 s at 0.5 m/s
      const control::Pose2 robot{0.005 * k, 0, 0};
      tr.step(robot, echoes(u, robot, {}, walls, &rng), k * 0.01);
      if (tr.nearest(robot)) ++person_ticks;
    }
    return std::pair{person_ticks, tr.counters().static_wall_trace};
  };
  const auto [with_ticks, traced] = run(true);
  const auto [without_ticks, untraced] = run(false);
  EXPECT_GT(without_ticks, 100) << "the case the trace is for: walls look like people walking alongside";
  EXPECT_EQ(with_ticks, 0);
  EXPECT_GT(traced, 1000u);
  EXPECT_EQ(untraced, 0u);
}

// A person crossing in front of the side sensor is not a wall trace: the
// echo points run across the robot's motion, not along it.
TEST(HumanTracker, APersonPassingTheSideIsStillTracked) {
  const config::UltrasonicConfig u;
  HumanTracker tr(u, {});
  std::mt19937 rng(7);
  int person_ticks = 0;
  for (int k = 0; k < 300; ++k) {
    const double t = k * 0.01;
    const control::Pose2 robot{0.005 * k, 0, 0};
    const Circle p{0.5 + 0.005 * k, 2.5 - 0.6 * t, 0.25};  // walking towards the robot's left side
    tr.step(robot, echoes(u, robot, {p}, {}, &rng), t);
    if (tr.nearest(robot)) ++person_ticks;
  }
  EXPECT_GT(person_ticks, 50);
}
