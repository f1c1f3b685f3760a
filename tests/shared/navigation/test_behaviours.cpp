// The behaviours and guards as pure functions, table-driven: go-to-goal
// (atan2 heading error, speed on distance, limits), avoid, boundary following
// (Eq 5.23 rotation, distance keeping), blending weight, side choice
// (Eq 5.24), clear shot (Eq 5.27), progress (Eq 5.25), parameter checks.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "shared/navigation/behaviours.hpp"
#include "shared/navigation/guards.hpp"
#include "shared/navigation/navigation_params.hpp"
#include "tests/shared/navigation/nav_test_values.hpp"

using namespace inspect;
using namespace inspect::navigation;
using inspect::test::kNaN;
using inspect::test::kPi;
using inspect::test::kSonar;

namespace {

const NavigationParams kP{};

// --- go-to-goal -----------------------------------------------------------------

struct GtgCase {
  const char* name;
  control::Pose2 pose;
  Vec2 goal;
  double v_m_s;
  double w_rad_s;
};

std::ostream& operator<<(std::ostream& os, const GtgCase& c) { return os << c.name; }

class GoToGoalTable : public ::testing::TestWithParam<GtgCase> {};

TEST_P(GoToGoalTable, TwistFromHeadingErrorAndDistance) {
  const GtgCase& c = GetParam();
  const control::Twist t = goToGoal(c.pose, c.goal, kP);
  EXPECT_NEAR(t.v_m_s, c.v_m_s, 1e-9);
  EXPECT_NEAR(t.w_rad_s, c.w_rad_s, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(
    Cases, GoToGoalTable,
    ::testing::Values(
        // Far ahead: capped at v_max, no turn.
        GtgCase{"far_ahead", {0, 0, 0}, {10, 0}, 0.5, 0.0},
        // Near: v = speed_kp * d (slows down toward the goal).
        GtgCase{"near_ahead", {0, 0, 0}, {0.4, 0}, 0.2, 0.0},
        // 30 deg to the left: w = kp * e, v shaped by cos(e).
        GtgCase{"left_30deg", {0, 0, 0}, {10 * std::cos(kPi / 6), 10 * std::sin(kPi / 6)}, 0.5 * std::cos(kPi / 6),
                2.0 * kPi / 6},
        // Heading error across +-pi is wrapped (robot at 170 deg, goal at -170 deg: turn +20 deg).
        GtgCase{"wraps_across_pi", {0, 0, 170.0 * kPi / 180}, {-10 * std::cos(kPi / 18), -10 * std::sin(kPi / 18)},
                0.5 * std::cos(kPi / 9), 2.0 * kPi / 9},
        // Goal behind: turn on the spot at the yaw-rate limit, no forward speed.
        GtgCase{"behind", {0, 0, 0}, {-3, 0.01}, 0.0, 1.5},
        GtgCase{"behind_right", {0, 0, 0}, {-3, -0.01}, 0.0, -1.5}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(Behaviours, LimitTwistClampsAndNeverReverses) {
  EXPECT_EQ(limitTwist({2.0, 5.0}, kP).v_m_s, kP.v_max_m_s);
  EXPECT_EQ(limitTwist({2.0, 5.0}, kP).w_rad_s, kP.w_max_rad_s);
  EXPECT_EQ(limitTwist({-1.0, -5.0}, kP).v_m_s, 0.0);
  EXPECT_EQ(limitTwist({-1.0, -5.0}, kP).w_rad_s, -kP.w_max_rad_s);
  EXPECT_EQ(limitTwist({std::nan(""), INFINITY}, kP).v_m_s, 0.0);
  EXPECT_EQ(limitTwist({std::nan(""), INFINITY}, kP).w_rad_s, 0.0);
  EXPECT_EQ(stop().v_m_s, 0.0);
  EXPECT_EQ(stop().w_rad_s, 0.0);
}

// --- avoid and boundary following ------------------------------------------------

ObstacleSummary wallOnLeftAt(double d) {
  // As summarise() reports a wall along the robot's left at distance d.
  ObstacleSummary s;
  s.any = true;
  s.nearest_m = d;
  s.nearest_point = {0, d};
  s.away_from_nearest = {0, -1};
  s.avoid = {0, -1};
  s.left = {d, {0, -1}, {0, -1}, d, true};
  s.right = {};
  return s;
}

TEST(Behaviours, AvoidSteersAlongTheAvoidVector) {
  const Steer s = avoidSteer({0, 0, 0}, wallOnLeftAt(0.5), kP);
  EXPECT_NEAR(s.heading_rad, -kPi / 2, 1e-12);
  EXPECT_EQ(s.speed_m_s, kP.avoid_speed_m_s);
  // Nothing to avoid: hold still.
  EXPECT_EQ(avoidSteer({0, 0, 0.3}, ObstacleSummary{}, kP).speed_m_s, 0.0);
}

struct FollowDirCase {
  Vec2 avoid;
  FollowSide side;
  Vec2 expected;
};

class FollowDirectionTable : public ::testing::TestWithParam<FollowDirCase> {};

TEST_P(FollowDirectionTable, AvoidRotatedByMinusOrPlusHalfPi) {
  const auto& c = GetParam();
  const Vec2 d = followDirection(c.avoid, c.side);
  EXPECT_NEAR(d.x, c.expected.x, 1e-12);
  EXPECT_NEAR(d.y, c.expected.y, 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Eq5_23, FollowDirectionTable,
                         ::testing::Values(
                             // Obstacle on the left (avoid points right): ccw goes forward.
                             FollowDirCase{{0, -1}, FollowSide::kCounterClockwise, {1, 0}},
                             FollowDirCase{{0, -1}, FollowSide::kClockwise, {-1, 0}},
                             // Obstacle ahead (avoid points back): cw turns left, ccw right.
                             FollowDirCase{{-2, 0}, FollowSide::kClockwise, {0, 1}},
                             FollowDirCase{{-2, 0}, FollowSide::kCounterClockwise, {0, -1}},
                             FollowDirCase{{0, 0}, FollowSide::kClockwise, {0, 0}},
                             FollowDirCase{{1, 0}, FollowSide::kNone, {0, 0}}));

struct KeepCase {
  double distance_m;
  double expected_heading_rad;
};

class FollowDistanceTable : public ::testing::TestWithParam<KeepCase> {};

TEST_P(FollowDistanceTable, DistanceKeepingLeansTowardOrAway) {
  const auto& c = GetParam();
  const Steer s = followSteer({0, 0, 0}, wallOnLeftAt(c.distance_m), FollowSide::kCounterClockwise, kP);
  EXPECT_NEAR(s.heading_rad, c.expected_heading_rad, 1e-9);
  EXPECT_EQ(s.speed_m_s, kP.follow_speed_m_s);
}

// Direction = (1, 0) - c (0, -1) with c = clamp(2.5 (d - 0.8), -1, 1): heading atan(c).
INSTANTIATE_TEST_SUITE_P(Cases, FollowDistanceTable,
                         ::testing::Values(KeepCase{0.8, 0.0}, KeepCase{0.9, std::atan(0.25)},
                                           KeepCase{0.7, -std::atan(0.25)}, KeepCase{2.0, kPi / 4},
                                           KeepCase{0.3, -kPi / 4}));

TEST(Behaviours, LostBoundaryCurvesTowardItsSide) {
  EXPECT_NEAR(followSteer({0, 0, 1.0}, ObstacleSummary{}, FollowSide::kCounterClockwise, kP).heading_rad,
              1.0 + kP.search_turn_rad, 1e-12);
  EXPECT_NEAR(followSteer({0, 0, 1.0}, ObstacleSummary{}, FollowSide::kClockwise, kP).heading_rad,
              1.0 - kP.search_turn_rad, 1e-12);
}

TEST(Behaviours, BlendWeightIsSmoothAndBounded) {
  EXPECT_EQ(blendWeight(std::numeric_limits<double>::infinity(), kP), 0.0);
  EXPECT_EQ(blendWeight(kP.caution_distance_m, kP), 0.0);
  EXPECT_DOUBLE_EQ(blendWeight(kP.guard_distance_m, kP), kP.blend_max_weight);
  EXPECT_DOUBLE_EQ(blendWeight(0.1, kP), kP.blend_max_weight);
  double prev = 0.0;
  for (double d = kP.caution_distance_m; d >= kP.guard_distance_m; d -= 0.01) {
    const double w = blendWeight(d, kP);
    EXPECT_GE(w, prev);
    EXPECT_LT(w - prev, 0.03);  // no jumps
    prev = w;
  }
}

TEST(Behaviours, BlendNeverStallsWhenAvoidOpposesGoal) {
  // Obstacle straight ahead between robot and goal: the blend still points at the goal.
  ObstacleSummary s;
  s.any = true;
  s.nearest_m = kP.guard_distance_m;
  s.avoid = {-1, 0};
  const Steer b = blendSteer({0, 0, 0}, {5, 0}, s, kP);
  EXPECT_NEAR(b.heading_rad, 0.0, 1e-12);
  EXPECT_GT(b.speed_m_s, 0.0);
  // Obstacle to the left: the blend veers right of the goal direction.
  s.avoid = {0, -1};
  EXPECT_LT(blendSteer({0, 0, 0}, {5, 0}, s, kP).heading_rad, -0.3);
}

// --- guards -------------------------------------------------------------------------

struct SideCase {
  const char* name;
  Vec2 avoid;
  Vec2 to_goal;
  Vec2 heading;
  FollowSide expected;
};

std::ostream& operator<<(std::ostream& os, const SideCase& c) { return os << c.name; }

class ChooseSideTable : public ::testing::TestWithParam<SideCase> {};

TEST_P(ChooseSideTable, AcuteAngleWithTheGoalDirection) {
  const auto& c = GetParam();
  EXPECT_EQ(chooseSide(c.avoid, c.to_goal, c.heading), c.expected);
}

INSTANTIATE_TEST_SUITE_P(
    Eq5_24, ChooseSideTable,
    ::testing::Values(
        // Wall ahead, goal ahead-left: cw (turning left, obstacle on the right).
        SideCase{"goal_left", {-1, 0}, {1, 1}, {1, 0}, FollowSide::kClockwise},
        SideCase{"goal_right", {-1, 0}, {1, -1}, {1, 0}, FollowSide::kCounterClockwise},
        // Goal straight behind the obstacle: the current heading decides, then ccw.
        SideCase{"tie_heading_left", {-1, 0}, {1, 0}, {1, 0.5}, FollowSide::kClockwise},
        SideCase{"tie_heading_right", {-1, 0}, {1, 0}, {1, -0.5}, FollowSide::kCounterClockwise},
        SideCase{"tie_straight", {-1, 0}, {1, 0}, {1, 0}, FollowSide::kCounterClockwise},
        // Wall on the left, goal ahead: ccw continues forward.
        SideCase{"wall_left_goal_ahead", {0, -1}, {1, 0}, {1, 0}, FollowSide::kCounterClockwise}),
    [](const auto& info) { return std::string(info.param.name); });

struct ClearCase {
  const char* name;
  Vec2 avoid;
  bool blocked;
  Vec2 to_goal;
  bool clear;
  bool goal_near = false;  // the goal lies within the guard distance
};

std::ostream& operator<<(std::ostream& os, const ClearCase& c) { return os << c.name; }

class ClearShotTable : public ::testing::TestWithParam<ClearCase> {};

TEST_P(ClearShotTable, AvoidAndGoalMakeAnAcuteAngle) {
  const auto& c = GetParam();
  ObstacleSummary s;
  s.any = norm(c.avoid) > 0.0;
  s.avoid = c.avoid;
  s.goal_blocked = c.blocked;
  s.goal_near = c.goal_near;
  EXPECT_EQ(clearShot(s, c.to_goal), c.clear);
}

INSTANTIATE_TEST_SUITE_P(Eq5_27, ClearShotTable,
                         ::testing::Values(ClearCase{"no_obstacle", {0, 0}, false, {1, 0}, true},
                                           ClearCase{"obstacle_between", {-1, 0}, false, {1, 0}, false},
                                           ClearCase{"obstacle_behind", {1, 0}, false, {1, 0}, true},
                                           ClearCase{"acute", {1, -1}, false, {1, 0}, true},
                                           ClearCase{"obtuse", {-1, -1}, false, {1, 0}, false},
                                           ClearCase{"perpendicular_is_not_clear", {0, -1}, false, {1, 0}, false},
                                           ClearCase{"corridor_blocked", {1, 0}, true, {1, 0}, false},
                                           // A near goal with a free corridor: nothing is in the way,
                                           // even with the obstacles pushing across the goal direction.
                                           ClearCase{"near_goal_free", {-1, -1}, false, {1, 0}, true, true},
                                           ClearCase{"near_goal_blocked", {1, 0}, true, {1, 0}, false, true}),
                         [](const auto& info) { return std::string(info.param.name); });

struct ProgressCase {
  double dist, d_tau, margin;
  bool progress;
};

class ProgressTable : public ::testing::TestWithParam<ProgressCase> {};

TEST_P(ProgressTable, CloserThanAtEntryByTheMargin) {
  const auto& c = GetParam();
  EXPECT_EQ(progressMade(c.dist, c.d_tau, c.margin), c.progress);
}

INSTANTIATE_TEST_SUITE_P(Eq5_25, ProgressTable,
                         ::testing::Values(ProgressCase{4.0, 5.0, 0.2, true}, ProgressCase{4.8, 5.0, 0.2, false},
                                           ProgressCase{4.79, 5.0, 0.2, true}, ProgressCase{6.0, 5.0, 0.2, false},
                                           ProgressCase{4.99, 5.0, 0.0, true},
                                           ProgressCase{1.0, std::numeric_limits<double>::infinity(), 0.2, true}));

// --- parameters -----------------------------------------------------------------------

TEST(Params, DefaultsAreValid) { EXPECT_EQ(checkParams(NavigationParams{}), ""); }

struct BadParam {
  const char* name;
  void (*set)(NavigationParams&);
};

std::ostream& operator<<(std::ostream& os, const BadParam& c) { return os << c.name; }

class BadParamTable : public ::testing::TestWithParam<BadParam> {};

TEST_P(BadParamTable, RejectedNamingTheParameter) {
  NavigationParams p;
  GetParam().set(p);
  const std::string err = checkParams(p);
  EXPECT_NE(err.find(GetParam().name), std::string::npos) << err;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, BadParamTable,
    ::testing::Values(BadParam{"v_max_m_s", [](NavigationParams& p) { p.v_max_m_s = 0.0; }},
                      BadParam{"w_max_rad_s", [](NavigationParams& p) { p.w_max_rad_s = std::nan(""); }},
                      BadParam{"min_dwell_s", [](NavigationParams& p) { p.min_dwell_s = -0.1; }},
                      BadParam{"safety_distance_m", [](NavigationParams& p) { p.safety_distance_m = 1.0; }},
                      BadParam{"guard_distance_m", [](NavigationParams& p) { p.guard_distance_m = 1.5; }},
                      BadParam{"follow_distance_m", [](NavigationParams& p) { p.follow_distance_m = 0.95; }},
                      BadParam{"follow_caution_m", [](NavigationParams& p) { p.follow_caution_m = 0.7; }},
                      BadParam{"blend_max_weight", [](NavigationParams& p) { p.blend_max_weight = 0.5; }},
                      BadParam{"memory_s", [](NavigationParams& p) { p.memory_s = INFINITY; }}),
    [](const auto& info) { return std::string(info.param.name); });

}  // namespace
