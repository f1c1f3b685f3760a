// The hybrid automaton open loop: poses and sonar ranges are fed in directly
// (the robot does not move with the twist), so each guard, reset and the
// switch counters can be checked tick by tick.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "shared/config/robot_config.hpp"
#include "shared/navigation/navigator.hpp"
#include "tests/shared/navigation/nav_test_values.hpp"

using namespace inspect;
using namespace inspect::navigation;
using inspect::test::kNaN;
using inspect::test::kPi;
using inspect::test::kSonar;

namespace {

constexpr double kTickDt_s = 0.01;

// Ranges with only the two front sensors echoing at range_m (a wall ahead at 0.30 + range_m).
SonarRanges front(double range_m) { return {range_m, range_m, kNaN, kNaN}; }
const SonarRanges kNone{kNaN, kNaN, kNaN, kNaN};

// Steps n ticks with the same input; returns the last output.
NavigationOutput hold(Navigator& nav, const control::Pose2& pose, const SonarRanges& r, int n) {
  NavigationOutput out;
  for (int i = 0; i < n; ++i) out = nav.step(pose, r, kTickDt_s);
  return out;
}

TEST(Automaton, WithoutGoalItStops) {
  Navigator nav({}, kSonar);
  const auto out = nav.step({0, 0, 0}, front(0.5), kTickDt_s);
  EXPECT_EQ(out.mode, Mode::kAtGoal);
  EXPECT_EQ(out.twist.v_m_s, 0.0);
  EXPECT_EQ(out.twist.w_rad_s, 0.0);
  EXPECT_FALSE(nav.hasGoal());
}

TEST(Automaton, BadParamsThrowAtConstruction) {
  NavigationParams p;
  p.guard_distance_m = 0.5;  // below the safety distance
  EXPECT_THROW(Navigator(p, kSonar), std::invalid_argument);
}

TEST(Automaton, FreeSpaceGoToGoalMatchesThePureBehaviour) {
  Navigator nav({}, kSonar);
  nav.setGoal({3.0, 1.0});
  const control::Pose2 pose{0.5, -0.2, 0.4};
  const auto out = nav.step(pose, kNone, kTickDt_s);
  EXPECT_EQ(out.mode, Mode::kGoToGoal);
  // With ki = kd = 0 the heading PID is the P law of the pure behaviour.
  const control::Twist t = goToGoal(pose, {3.0, 1.0}, NavigationParams{});
  EXPECT_NEAR(out.twist.v_m_s, t.v_m_s, 1e-12);
  EXPECT_NEAR(out.twist.w_rad_s, t.w_rad_s, 1e-12);
  EXPECT_NEAR(out.distance_to_goal_m, std::hypot(2.5, 1.2), 1e-12);
  EXPECT_TRUE(std::isinf(out.nearest_obstacle_m));
  EXPECT_EQ(out.switch_count, 0u);
}

TEST(Automaton, NonFiniteInputStopsWithoutChangingState) {
  Navigator nav({}, kSonar);
  nav.setGoal({3.0, 0.0});
  hold(nav, {0, 0, 0}, kNone, 5);
  const auto bad_pose = nav.step({kNaN, 0, 0}, kNone, kTickDt_s);
  EXPECT_EQ(bad_pose.twist.v_m_s, 0.0);
  EXPECT_EQ(bad_pose.twist.w_rad_s, 0.0);
  EXPECT_EQ(bad_pose.mode, Mode::kGoToGoal);
  const auto bad_dt = nav.step({0, 0, 0}, kNone, 0.0);
  EXPECT_EQ(bad_dt.twist.v_m_s, 0.0);
  EXPECT_EQ(nav.step({0, 0, 0}, kNone, -kTickDt_s).twist.v_m_s, 0.0);
  EXPECT_GT(nav.step({0, 0, 0}, kNone, kTickDt_s).twist.v_m_s, 0.0);  // recovers
}

TEST(Automaton, ObstacleInTheWayEntersBoundaryAfterTheDwellTimeWithReset) {
  Navigator nav({}, kSonar);
  nav.setGoal({5.0, 1.0});
  // Wall ahead at 0.30 + 0.45 = 0.75 m: inside the guard (0.9), outside safety (0.6).
  const auto first = nav.step({0, 0, 0}, front(0.45), kTickDt_s);
  EXPECT_EQ(first.mode, Mode::kGoToGoal);  // dwell time (0.3 s) not over yet
  EXPECT_FALSE(first.clear_shot);
  int k = 1;
  NavigationOutput out = first;
  while (out.mode == Mode::kGoToGoal && k < 100) {
    out = nav.step({0, 0, 0}, front(0.45), kTickDt_s);
    ++k;
  }
  EXPECT_GE(k * kTickDt_s, NavigationParams{}.min_dwell_s - 1e-9);
  EXPECT_LE(k * kTickDt_s, NavigationParams{}.min_dwell_s + 2 * kTickDt_s);
  // Goal to the left of the wall: the side heading left (clockwise round the obstacle).
  EXPECT_EQ(out.mode, Mode::kFollowCw);
  EXPECT_EQ(out.side, FollowSide::kClockwise);
  EXPECT_TRUE(out.switched);
  EXPECT_EQ(out.switch_count, 1u);
  EXPECT_NEAR(out.progress_reference_m, std::hypot(5.0, 1.0), 1e-12);  // reset: d_tau = |x - x_g|
  EXPECT_GT(out.twist.w_rad_s, 0.0);                                    // turning left
}

TEST(Automaton, DangerouslyCloseIsAvoidedAtOnce) {
  Navigator nav({}, kSonar);
  nav.setGoal({5.0, 0.0});
  const auto out = nav.step({0, 0, 0}, front(0.2), kTickDt_s);  // 0.5 m < safety 0.6 m, first tick
  EXPECT_EQ(out.mode, Mode::kAvoid);
  EXPECT_EQ(out.switch_count, 1u);
  EXPECT_EQ(out.twist.v_m_s, 0.0);  // turns away on the spot (avoid points backward)
  EXPECT_NE(out.twist.w_rad_s, 0.0);
  EXPECT_NE(out.side, FollowSide::kNone);  // AVOID from GO_TO_GOAL starts a boundary episode
  EXPECT_NEAR(out.progress_reference_m, 5.0, 1e-12);
}

TEST(Automaton, LeavingTheBoundaryNeedsAClearShotAndProgress) {
  NavigationParams p;
  p.memory_s = 0.0;  // only this tick's echoes: each pose sees exactly what it is given
  Navigator nav(p, kSonar);
  nav.setGoal({5.0, 0.0});
  // Enter the boundary at the origin: d_tau = 5.
  auto out = hold(nav, {0, 0, 0}, front(0.45), 40);
  ASSERT_TRUE(out.mode == Mode::kFollowCw || out.mode == Mode::kFollowCcw);
  ASSERT_NEAR(out.progress_reference_m, 5.0, 1e-12);
  // Facing away from the goal with an obstacle in front of it (i.e. behind the robot
  // as seen from the goal): a clear shot (Eq 5.27), but at 6 m from the goal no progress.
  out = hold(nav, {-1.0, 0, kPi}, front(0.5), 100);
  EXPECT_TRUE(out.clear_shot);
  EXPECT_FALSE(out.progress);
  EXPECT_TRUE(out.mode == Mode::kFollowCw || out.mode == Mode::kFollowCcw);
  // Progress without a clear shot (obstacle between robot and goal) does not leave either.
  out = hold(nav, {2.0, 0, 0}, front(0.45), 100);
  EXPECT_FALSE(out.clear_shot);
  EXPECT_TRUE(out.progress);
  EXPECT_TRUE(out.mode == Mode::kFollowCw || out.mode == Mode::kFollowCcw);
  // Both: back to go-to-goal.
  out = nav.step({2.0, 0, kPi}, front(0.5), kTickDt_s);
  EXPECT_TRUE(out.clear_shot);
  EXPECT_TRUE(out.progress);
  EXPECT_EQ(out.mode, Mode::kGoToGoal);
  EXPECT_EQ(out.switch_count, 2u);
}

TEST(Automaton, AtGoalStopsWithHysteresis) {
  const NavigationParams p;
  Navigator nav(p, kSonar);
  nav.setGoal({1.0, 0.0});
  auto out = nav.step({1.0 - p.goal_epsilon_m / 2, 0, 0}, kNone, kTickDt_s);
  EXPECT_EQ(out.mode, Mode::kAtGoal);
  EXPECT_EQ(out.twist.v_m_s, 0.0);
  EXPECT_EQ(out.twist.w_rad_s, 0.0);
  // Pushed a little away (less than epsilon + release): stays stopped.
  out = hold(nav, {1.0 - p.goal_epsilon_m - p.goal_release_m / 2, 0, 0}, kNone, 50);
  EXPECT_EQ(out.mode, Mode::kAtGoal);
  // Pushed farther: goes back to the goal.
  out = nav.step({1.0 - p.goal_epsilon_m - 2 * p.goal_release_m, 0, 0}, kNone, kTickDt_s);
  EXPECT_EQ(out.mode, Mode::kGoToGoal);
  EXPECT_EQ(out.switch_count, 2u);
  // A new goal restarts the counters.
  nav.setGoal({3.0, 0.0});
  EXPECT_EQ(nav.step({0, 0, 0}, kNone, kTickDt_s).switch_count, 0u);
}

TEST(Automaton, MemoryKeepsAWallWhileTheSensorsLookAway) {
  const NavigationParams p;
  Navigator nav(p, kSonar);
  nav.setGoal({5.0, 0.0});
  hold(nav, {0, 0, 0}, front(1.0), 10);
  // The sonars now see nothing (the robot turned): the wall is still known ...
  auto out = hold(nav, {0, 0, kPi / 2}, kNone, static_cast<int>(p.memory_s / kTickDt_s) - 20);
  EXPECT_NEAR(out.nearest_obstacle_m, std::hypot(1.3, 0.12), 0.01);
  EXPECT_NEAR(out.nearest_bearing_rad, -kPi / 2, 0.1);  // to the robot's right now
  // ... until it is older than memory_s.
  out = hold(nav, {0, 0, kPi / 2}, kNone, 40);
  EXPECT_TRUE(std::isinf(out.nearest_obstacle_m));
}

// --- chattering: prevention and counting ------------------------------------------

struct ChatterCase {
  const char* name;
  double dwell_s;
  double hysteresis_m;
  unsigned expected_switches;
  unsigned expected_rapid;
};

std::ostream& operator<<(std::ostream& os, const ChatterCase& c) { return os << c.name; }

class ChatterTable : public ::testing::TestWithParam<ChatterCase> {};

TEST_P(ChatterTable, SwitchesAroundTheSafetyDistance) {
  // A wall ahead whose echo alternates every tick between 0.58 m and 0.62 m
  // from the robot, around the 0.60 m safety distance, for 1 s (100 ticks).
  const ChatterCase& c = GetParam();
  NavigationParams p;
  p.memory_s = 0.0;
  p.min_dwell_s = c.dwell_s;
  p.distance_hysteresis_m = c.hysteresis_m;
  Navigator nav(p, kSonar);
  nav.setGoal({5.0, 0.0});
  NavigationOutput out;
  unsigned seen = 0;
  for (int k = 0; k < 100; ++k) {
    out = nav.step({0, 0, 0}, front(k % 2 == 0 ? 0.28 : 0.32), kTickDt_s);
    if (out.switched) ++seen;
  }
  EXPECT_EQ(out.switch_count, c.expected_switches);
  EXPECT_EQ(out.switch_count, seen);  // the counter counts exactly the switches
  EXPECT_EQ(out.rapid_switch_count, c.expected_rapid);
}

INSTANTIATE_TEST_SUITE_P(
    Cases, ChatterTable,
    ::testing::Values(
        // No protection: GO_TO_GOAL -> AVOID, then AVOID <-> FOLLOW on every tick (Zeno-like).
        ChatterCase{"unprotected", 0.0, 0.0, 100, 99},
        // Hysteresis (leave AVOID only beyond 0.68 m): one switch into AVOID, none back.
        ChatterCase{"hysteresis", 0.0, 0.08, 1, 0},
        // Dwell time 0.3 s: AVOID is left only after 0.3 s, and the (safety-first, immediate)
        // re-entry follows on the next tick: switches at ticks 0, 31/32, 63/64, 95/96, all
        // but the first within the 0.5 s chatter window of the one before.
        ChatterCase{"dwell", 0.3, 0.0, 7, 6},
        // Both (the defaults).
        ChatterCase{"defaults", 0.3, 0.08, 1, 0}),
    [](const auto& info) { return std::string(info.param.name); });

}  // namespace
