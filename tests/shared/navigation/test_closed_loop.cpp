// Closed-loop navigation: the Navigator drives the simulator's plant (first-
// order hub motors, the paper's geometry, a body that cannot pass walls) at
// 100 Hz, fed by the simulator's ultrasonic model (7 rays across each 30 deg
// cone, nearest hit, +-0.03 m noise, seeded) in worlds built from YAML text.
// Every run is bounded in steps. Set NAV_TRACE_DIR to write each run's
// trajectory as CSV (t, pose, twist, mode, nearest, gap, switches).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "shared/config/config_node.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/navigation/navigator.hpp"
#include "sim/robot_plant.hpp"
#include "sim/ultrasonic_model.hpp"
#include "shared/world/world.hpp"
#include "tests/support/paths.hpp"

using namespace inspect;
using navigation::FollowSide;
using navigation::Mode;
using navigation::NavigationParams;
using navigation::Vec2;

namespace {

constexpr double kDt = 0.01;          // 100 Hz, the robot's control rate
constexpr double kNoCollisionGap = 0.1;  // body edge to the nearest wall, m: "never closer than body + margin"

world::World worldOf(const std::string& yaml) {
  return world::loadWorldText(yaml, "nav_test_world.yaml");
}

bool following(Mode m) { return m == Mode::kFollowCw || m == Mode::kFollowCcw; }

struct NavRun {
  bool reached = false;           // AT_GOAL and the wheels stopped
  int steps = 0;                  // ticks until reached (or the bound)
  double time_s = 0.0;
  double min_gap_m = std::numeric_limits<double>::infinity();  // min of clearance - body radius
  bool blocked = false;           // the plant refused a move into a wall
  double final_distance_m = 0.0;
  double path_m = 0.0;
  navigation::NavigationOutput last;
  std::vector<Mode> modes{Mode::kGoToGoal};  // modes in the order entered
  std::vector<FollowSide> sides;             // side chosen at each boundary entry from GO_TO_GOAL
  std::vector<control::Pose2> poses;         // true pose after each tick
  std::vector<int> entry_steps;              // tick of each boundary entry from GO_TO_GOAL
  int clear_without_progress = 0;   // ticks following with a clear shot (Eq 5.27) but no progress (Eq 5.25)
  int left_without_progress = 0;    // FOLLOW -> GO_TO_GOAL switches taken without progress
  double command_variation = 0.0;   // sum of |delta w| over the run, rad/s
  std::vector<double> goals_reached_s;  // route: when each goal before the last was reached
};

struct RunSpec {
  std::string name;
  std::string world_yaml;
  Vec2 goal;
  NavigationParams params{};
  int max_steps = 6000;
  uint64_t seed = 7;
  std::vector<Vec2> then{};  // further goals, each set when the previous one is reached (a route)
};

NavRun runNav(const RunSpec& spec) {
  const world::World world = worldOf(spec.world_yaml);
  const config::RobotConfig robot;
  const sim::RobotPlant plant(robot, world);
  sim::UltrasonicModel sonar(robot.ultrasonic, spec.seed);
  navigation::Navigator nav(spec.params, robot.ultrasonic);
  nav.setGoal(spec.goal);

  std::ofstream trace;
  if (const char* dir = std::getenv("NAV_TRACE_DIR")) {
    trace.open(std::string(dir) + "/" + spec.name + ".csv");
    trace << "t_s,x_m,y_m,theta_rad,v_m_s,w_rad_s,mode,nearest_m,gap_m,switches\n";
  }

  const double body = robot.geometry.body_radius_m;
  sim::PlantState st;
  st.pose = world.start;
  NavRun r;
  r.poses.reserve(static_cast<std::size_t>(spec.max_steps));
  int stopped_ticks = 0;
  double prev_w = 0.0;
  Vec2 goal = spec.goal;
  std::size_t next_goal = 0;
  for (int k = 0; k < spec.max_steps; ++k) {
    const auto ranges = navigation::rangesFromMm(sonar.measureAllMm(world, st.pose));
    const auto& out = nav.step(st.pose, ranges, kDt);
    if (out.mode == Mode::kAtGoal && next_goal < spec.then.size()) {
      r.goals_reached_s.push_back(k * kDt);
      goal = spec.then[next_goal++];
      nav.setGoal(goal);  // as RobotCore runs a route: the memory is kept
    }
    if (out.switched) {
      const Mode prev = r.modes.back();
      r.modes.push_back(out.mode);
      if (following(out.mode) && prev == Mode::kGoToGoal) {
        r.sides.push_back(out.side);
        r.entry_steps.push_back(k);
      }
      if (following(prev) && out.mode == Mode::kGoToGoal && !out.progress) ++r.left_without_progress;
    }
    if (following(out.mode) && out.clear_shot && !out.progress) ++r.clear_without_progress;
    r.command_variation += std::abs(out.twist.w_rad_s - prev_w);
    prev_w = out.twist.w_rad_s;

    const auto twist = control::limitTwist(out.twist, robot.geometry.wheel_radius_m, robot.geometry.track_m,
                                           robot.limits.max_wheel_speed_rad_s);
    const auto set = control::wheelsFromTwist(twist, robot.geometry.wheel_radius_m, robot.geometry.track_m);
    const control::Pose2 before = st.pose;
    const auto ps = plant.step(st, set, kDt);
    st = ps.state;
    r.poses.push_back(st.pose);
    r.blocked = r.blocked || ps.blocked;
    r.path_m += std::hypot(st.pose.x_m - before.x_m, st.pose.y_m - before.y_m);
    const double gap = world::clearance(world, {st.pose.x_m, st.pose.y_m}) - body;
    r.min_gap_m = std::min(r.min_gap_m, gap);
    r.last = out;
    if (trace.is_open())
      trace << k * kDt << ',' << st.pose.x_m << ',' << st.pose.y_m << ',' << st.pose.theta_rad << ','
            << out.twist.v_m_s << ',' << out.twist.w_rad_s << ',' << navigation::toString(out.mode) << ','
            << out.nearest_obstacle_m << ',' << gap << ',' << out.switch_count << '\n';
    const double wheel = std::max(std::abs(st.wheel.left_rad_s), std::abs(st.wheel.right_rad_s));
    stopped_ticks = (out.mode == Mode::kAtGoal && wheel < 0.05) ? stopped_ticks + 1 : 0;
    r.steps = k + 1;
    if (stopped_ticks >= 20) {
      r.reached = true;
      break;
    }
  }
  r.time_s = r.steps * kDt;
  r.final_distance_m = std::hypot(goal.x - st.pose.x_m, goal.y - st.pose.y_m);
  std::printf("[nav] %-20s reached=%d t=%6.2fs steps=%5d path=%5.2fm min_gap=%.3fm switches=%u rapid=%u "
              "final=%.3fm sum|dw|=%.1f\n",
              spec.name.c_str(), r.reached, r.time_s, r.steps, r.path_m, r.min_gap_m, r.last.switch_count,
              r.last.rapid_switch_count, r.final_distance_m, r.command_variation);
  return r;
}

NavigationParams blendParams() {
  NavigationParams p;
  p.style = navigation::SwitchingStyle::kBlend;
  return p;
}

// --- worlds (docs/world-format.md) -----------------------------------------------

const std::string kFree = "name: free\nstart: {x_m: 0, y_m: 0, theta_rad: 0}\n";

// A 1.5 m x 2 m box straight between start (0, 0) and goal (8, 0).
const std::string kBox = R"(name: box
start: {x_m: 0, y_m: 0, theta_rad: 0}
obstacles:
  - name: box
    vertices_m: [3.5, -1.0,  5.0, -1.0,  5.0, 1.0,  3.5, 1.0]
)";

// The same box moved up: the straight line grazes its lower edge (0.3 m).
const std::string kBoxOffset = R"(name: box_offset
start: {x_m: 0, y_m: 0, theta_rad: 0}
obstacles:
  - name: box
    vertices_m: [3.5, 0.3,  5.0, 0.3,  5.0, 2.3,  3.5, 2.3]
)";

// A U open toward the robot (inside 2 m deep, 2.4 m wide); the goal (9, 0) is behind it.
const std::string kU = R"(name: u_trap
start: {x_m: 0, y_m: 0.1, theta_rad: 0}
obstacles:
  - name: u
    vertices_m: [3.0, 1.5,  5.3, 1.5,  5.3, -1.5,  3.0, -1.5,  3.0, -1.2,  5.0, -1.2,  5.0, 1.2,  3.0, 1.2]
)";

// A thin wall across the way with a 2.0 m gap (y 0.6 .. 2.6) to the left of the straight line.
const std::string kGap = R"(name: wall_gap
start: {x_m: 0, y_m: 0, theta_rad: 0}
walls:
  - {from_m: [3, -4], to_m: [3, 0.6]}
  - {from_m: [3, 2.6], to_m: [3, 6]}
)";

// The chapter's exercise (Fig 5.15): a 14 m x 10 m hall, an assembly line
// hanging from the top wall and a wall standing on the floor; the goal (12, 7)
// lies behind both, so two boundary episodes are needed.
const std::string kWarehouse = R"(name: warehouse
start: {x_m: 1, y_m: 8, theta_rad: 0}
walls:
  - {points_m: [0, 0,  14, 0,  14, 10,  0, 10], closed: true}
  - {from_m: [8, 0], to_m: [8, 6]}
obstacles:
  - name: assembly_line
    vertices_m: [3.0, 3.5,  4.2, 3.5,  4.2, 10.0,  3.0, 10.0]
)";

// The same hall with a 1.2 m return on top of the floor-standing wall (a
// concave corner, then the thin end of the return to round): rounding that
// end, the end leaves the sonars' view and, after memory_s, the memory, long
// before the half turn is done (config/worlds/warehouse.yaml has this shape).
const std::string kWarehouseReturn = R"(name: warehouse_return
start: {x_m: 1, y_m: 8, theta_rad: 0}
walls:
  - {points_m: [0, 0,  14, 0,  14, 10,  0, 10], closed: true}
  - {points_m: [8.0, 0.0,  8.0, 6.0,  6.8, 6.0]}
obstacles:
  - name: assembly_line
    vertices_m: [3.0, 3.5,  4.2, 3.5,  4.2, 10.0,  3.0, 10.0]
)";

// A 12 m thin wall across the way (side choice, chattering).
const std::string kLongWall = R"(name: long_wall
start: {x_m: 0, y_m: 0, theta_rad: 0}
walls:
  - {from_m: [2.5, -6], to_m: [2.5, 6]}
)";

// --- reaching the goal: table of scenarios ------------------------------------

struct ReachCase {
  const char* name;
  const std::string* world;
  Vec2 goal;
  bool blend;
  int max_steps;
  int min_boundary_episodes;  // boundary entries from GO_TO_GOAL at least
};

std::ostream& operator<<(std::ostream& os, const ReachCase& c) { return os << c.name; }

class NavReach : public ::testing::TestWithParam<ReachCase> {};

TEST_P(NavReach, ReachesGoalWithoutCollisionAndStops) {
  const ReachCase& c = GetParam();
  const NavRun r = runNav({c.name, *c.world, c.goal, c.blend ? blendParams() : NavigationParams{}, c.max_steps});
  EXPECT_TRUE(r.reached) << "bound " << c.max_steps << " steps";
  EXPECT_LT(r.final_distance_m, NavigationParams{}.goal_epsilon_m + 0.02);
  EXPECT_EQ(r.last.mode, Mode::kAtGoal);
  EXPECT_EQ(r.last.twist.v_m_s, 0.0);
  EXPECT_EQ(r.last.twist.w_rad_s, 0.0);
  EXPECT_FALSE(r.blocked);
  EXPECT_GT(r.min_gap_m, kNoCollisionGap);
  EXPECT_GE(static_cast<int>(r.sides.size()), c.min_boundary_episodes);
  EXPECT_EQ(r.left_without_progress, 0);
  EXPECT_EQ(r.last.rapid_switch_count, 0u);
}

INSTANTIATE_TEST_SUITE_P(
    Scenarios, NavReach,
    ::testing::Values(ReachCase{"free", &kFree, {4.0, 3.0}, false, 2500, 0},
                      ReachCase{"convex_box", &kBox, {8.0, 0.0}, false, 4500, 1},
                      ReachCase{"convex_box_blend", &kBox, {8.0, 0.0}, true, 4500, 1},
                      ReachCase{"box_offset", &kBoxOffset, {8.0, 0.0}, false, 4000, 0},
                      ReachCase{"box_offset_blend", &kBoxOffset, {8.0, 0.0}, true, 4000, 0},
                      ReachCase{"concave_u", &kU, {9.0, 0.0}, false, 7000, 1},
                      ReachCase{"wall_gap", &kGap, {6.0, 1.0}, false, 4000, 1},
                      ReachCase{"warehouse", &kWarehouse, {12.0, 7.0}, false, 9000, 2},
                      ReachCase{"warehouse_return", &kWarehouseReturn, {12.0, 7.0}, false, 9000, 2}),
    [](const auto& info) { return std::string(info.param.name); });

// --- specific behaviour -----------------------------------------------------------

TEST(NavClosedLoop, FreeSpaceIsOneStraightGoToGoal) {
  const NavRun r = runNav({"free_straight", kFree, {4.0, 3.0}, {}, 2500});
  ASSERT_TRUE(r.reached);
  EXPECT_EQ(r.last.switch_count, 1u);  // GO_TO_GOAL -> AT_GOAL only
  EXPECT_LT(r.path_m, 5.0 * 1.03);     // the straight line is 5 m
  // It stops: the last 10 poses are the same within a millimetre.
  const auto& a = r.poses[r.poses.size() - 10];
  const auto& b = r.poses.back();
  EXPECT_LT(std::hypot(a.x_m - b.x_m, a.y_m - b.y_m), 1e-3);
}

TEST(NavClosedLoop, WallGapIsPassedThroughTheGap) {
  const NavRun r = runNav({"wall_gap_crossing", kGap, {6.0, 1.0}, {}, 4000});
  ASSERT_TRUE(r.reached);
  // Where the robot crossed the wall's line x = 3: inside the gap, not round an end.
  double cross_y = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 1; i < r.poses.size(); ++i)
    if (r.poses[i - 1].x_m < 3.0 && r.poses[i].x_m >= 3.0) {
      cross_y = r.poses[i].y_m;
      break;
    }
  EXPECT_GT(cross_y, 0.6 + 0.45);
  EXPECT_LT(cross_y, 2.6 - 0.45);
  EXPECT_LT(r.path_m, 9.0);
}

TEST(NavClosedLoop, ConcaveUNeedsProgressToLeaveTheBoundary) {
  // Inside the U, following the inner arm back toward the opening, the goal
  // direction and the avoid vector make an acute angle: a clear shot (Eq 5.27)
  // while farther from the goal than at the boundary entry. Leaving there
  // would drive back into the U; the progress guard (Eq 5.25) keeps following.
  const NavRun r = runNav({"concave_u_progress", kU, {9.0, 0.0}, {}, 7000});
  ASSERT_TRUE(r.reached);
  EXPECT_GT(r.clear_without_progress, 50);  // the situation did occur (ticks)
  EXPECT_EQ(r.left_without_progress, 0);    // and never led out of the boundary
  // The first boundary entry was inside the U, and the robot left the U through its opening.
  ASSERT_FALSE(r.entry_steps.empty());
  const auto& entry = r.poses[static_cast<std::size_t>(r.entry_steps[0])];
  EXPECT_GT(entry.x_m, 3.0);
  EXPECT_LT(std::abs(entry.y_m), 1.2);
  double min_x_after = 1e9;
  for (std::size_t i = static_cast<std::size_t>(r.entry_steps[0]); i < r.poses.size(); ++i)
    min_x_after = std::min(min_x_after, r.poses[i].x_m);
  EXPECT_LT(min_x_after, 3.0);
}

TEST(NavClosedLoop, WarehouseTwoBoundaryEpisodesAsInTheExercise) {
  const NavRun r = runNav({"warehouse_episodes", kWarehouse, {12.0, 7.0}, {}, 9000});
  ASSERT_TRUE(r.reached);
  ASSERT_GE(r.sides.size(), 2u);
  // Assembly line: goal below the start -> follow down (obstacle on the left, ccw);
  // floor-standing wall: goal above the hit point -> follow up (obstacle on the right, cw).
  // (Leaving the wall at its top end with the end still near may re-enter once, same side.)
  EXPECT_EQ(r.sides[0], FollowSide::kCounterClockwise);
  for (std::size_t i = 1; i < r.sides.size(); ++i) EXPECT_EQ(r.sides[i], FollowSide::kClockwise) << i;
  EXPECT_LE(r.sides.size(), 3u);
  EXPECT_LT(r.path_m, 25.0);
}

struct WallSideCase {
  const char* name;
  Vec2 goal;
  FollowSide expected;
  double direction;  // +1: the robot must move to +y along the wall, -1: to -y
};

std::ostream& operator<<(std::ostream& os, const WallSideCase& c) { return os << c.name; }

class NavSide : public ::testing::TestWithParam<WallSideCase> {};

TEST_P(NavSide, FollowsOnTheSideThatHeadsTowardTheGoal) {
  const WallSideCase& c = GetParam();
  const NavRun r = runNav({c.name, kLongWall, c.goal, {}, 6000});
  ASSERT_GE(r.sides.size(), 1u);
  EXPECT_EQ(r.sides[0], c.expected);
  // One second after the entry the robot has moved along the wall toward the goal's side.
  const auto k0 = static_cast<std::size_t>(r.entry_steps[0]);
  ASSERT_LT(k0 + 150, r.poses.size());
  EXPECT_GT(c.direction * (r.poses[k0 + 150].y_m - r.poses[k0].y_m), 0.15);
  EXPECT_TRUE(r.reached);
  EXPECT_GT(r.min_gap_m, kNoCollisionGap);
}

INSTANTIATE_TEST_SUITE_P(LongWall, NavSide,
                         ::testing::Values(WallSideCase{"goal_left", {5.0, 2.0}, FollowSide::kClockwise, +1.0},
                                           WallSideCase{"goal_right", {5.0, -2.0}, FollowSide::kCounterClockwise, -1.0}),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(NavClosedLoop, HardAndBlendedBothReachTheConvexGoal) {
  const NavRun hard = runNav({"box_hard", kBox, {8.0, 0.0}, {}, 4500});
  const NavRun blend = runNav({"box_blend", kBox, {8.0, 0.0}, blendParams(), 4500});
  EXPECT_TRUE(hard.reached);
  EXPECT_TRUE(blend.reached);
  EXPECT_GT(hard.min_gap_m, kNoCollisionGap);
  EXPECT_GT(blend.min_gap_m, kNoCollisionGap);
  // Both take a path of similar length round the 1.5 m x 2 m box (straight line 8 m).
  EXPECT_LT(hard.path_m, 11.0);
  EXPECT_LT(blend.path_m, 11.0);
}

TEST(NavClosedLoop, ChatteringAtTheSafetyDistanceIsPreventedAndCounted) {
  // Following the wall right at the AVOID guard (follow distance 0.61 m,
  // safety distance 0.60 m, sonar noise +-0.03 m) makes FOLLOW <-> AVOID
  // flip on noise. Without dwell time and hysteresis it chatters; with the
  // defaults it does not.
  NavigationParams edge;
  edge.follow_distance_m = 0.61;
  NavigationParams bare = edge;
  bare.min_dwell_s = 0.0;
  bare.distance_hysteresis_m = 0.0;
  const NavRun unprotected = runNav({"chatter_unprotected", kLongWall, {5.0, 2.0}, bare, 7000});
  const NavRun protected_ = runNav({"chatter_protected", kLongWall, {5.0, 2.0}, edge, 7000});
  EXPECT_GE(unprotected.last.rapid_switch_count, 5u);  // the case does chatter
  // Protected: at most the one switch that no dwell may delay - into AVOID on
  // noise right after leaving the boundary, which is followed at 0.61 m.
  EXPECT_LE(protected_.last.rapid_switch_count, 1u);
  EXPECT_LT(protected_.last.switch_count, unprotected.last.switch_count);
  EXPECT_LE(protected_.last.switch_count, 15u);
  // The counter counts every change of mode seen by the caller.
  EXPECT_EQ(protected_.last.switch_count, protected_.modes.size() - 1);
  EXPECT_EQ(unprotected.last.switch_count, unprotected.modes.size() - 1);
  EXPECT_TRUE(protected_.reached);
}

TEST(NavClosedLoop, DeterministicForTheSameInput) {
  const NavRun a = runNav({"determinism_a", kBox, {8.0, 0.0}, {}, 4500});
  const NavRun b = runNav({"determinism_b", kBox, {8.0, 0.0}, {}, 4500});
  ASSERT_EQ(a.poses.size(), b.poses.size());
  EXPECT_EQ(a.poses.back().x_m, b.poses.back().x_m);
  EXPECT_EQ(a.poses.back().y_m, b.poses.back().y_m);
  EXPECT_EQ(a.last.switch_count, b.last.switch_count);
}

}  // namespace

namespace {

// config/worlds/square_room.yaml: a closed 8 m x 8 m room, the robot at (2, 4)
// facing the 0.6 m box at x 5.6..6.2; 1.8 m between the box and the east wall.
const std::string kSquareRoom = R"(name: square_room
start: {x_m: 2.0, y_m: 4.0, theta_rad: 0.0}
walls:
  - points_m: [0.0, 0.0,  8.0, 0.0,  8.0, 8.0,  0.0, 8.0]
    closed: true
obstacles:
  - name: box
    vertices_m: [5.6, 3.7,  6.2, 3.7,  6.2, 4.3,  5.6, 4.3]
)";

struct RoomCase {
  const char* name;
  Vec2 goal;
  uint64_t seed;
};

std::ostream& operator<<(std::ostream& os, const RoomCase& c) { return os << c.name; }

class NavSquareRoom : public ::testing::TestWithParam<RoomCase> {};

}  // namespace

// Goals behind the box, between it and the east wall. Before the fix the
// wall beyond the goal "blocked" the corridor to a goal 0.2 m away (the
// corridor reached the guard distance, past the goal), the boundary was
// re-entered there with d_tau ~0.2 m - below the progress margin, so never
// left - and the robot followed the room's outer wall for good. 46 of 135
// goals on a grid behind the box failed then; after, only goals within the
// safety distance of a surface do (documented limit).
TEST_P(NavSquareRoom, GoalBehindTheBoxIsReachedNotTheOuterWallFollowed) {
  const RoomCase& c = GetParam();
  RunSpec spec{c.name, kSquareRoom, c.goal, {}, 4000};
  spec.seed = c.seed;
  const NavRun r = runNav(spec);
  EXPECT_TRUE(r.reached) << "bound 4000 steps";
  EXPECT_GT(r.min_gap_m, kNoCollisionGap);
  EXPECT_LT(r.path_m, 10.0) << "round the box, not round the room";
  EXPECT_EQ(r.left_without_progress, 0);
}

INSTANTIATE_TEST_SUITE_P(
    BehindTheBox, NavSquareRoom,
    ::testing::Values(RoomCase{"behind_south", {7.0, 3.5}, 7}, RoomCase{"behind_south_seed8", {7.0, 3.5}, 8},
                      RoomCase{"behind_centre", {7.2, 4.0}, 8}, RoomCase{"near_wall_south", {7.4, 3.0}, 7},
                      RoomCase{"near_wall_north", {7.4, 5.0}, 7}, RoomCase{"behind_north", {7.3, 5.0}, 7}),
    [](const auto& info) { return std::string(info.param.name); });

// The shipped example route (config/routes/warehouse_tour.yaml, odometry
// frame = the room's start pose) is driven in the square room: every point
// reached, no collision.
TEST(NavClosedLoop, ExampleRouteIsDrivableInTheSquareRoom) {
  const auto root = config::ConfigNode::loadFile(inspect::test::srcPath("config/routes/warehouse_tour.yaml"));
  const std::vector<double> xy = root.numbers("waypoints_m");
  ASSERT_GE(xy.size(), 4u);
  ASSERT_EQ(xy.size() % 2, 0u);
  // Odometry frame -> the world frame of the test: the start pose is (2, 4) facing +x.
  std::vector<Vec2> goals;
  for (std::size_t i = 0; i + 1 < xy.size(); i += 2) goals.push_back({xy[i] + 2.0, xy[i + 1] + 4.0});
  NavigationParams params;
  params.v_max_m_s = root.number("speed_m_s", params.v_max_m_s, 0.01, 1.0);
  RunSpec spec{"example_route", kSquareRoom, goals.front(), params, 15000};
  spec.then.assign(goals.begin() + 1, goals.end());
  const NavRun r = runNav(spec);
  EXPECT_TRUE(r.reached);
  EXPECT_EQ(r.goals_reached_s.size(), goals.size() - 1);
  EXPECT_GT(r.min_gap_m, kNoCollisionGap);
  EXPECT_FALSE(r.blocked);
}

TEST(NavClosedLoop, ThinWallEndIsRoundedAfterItLeavesTheMemory) {
  // Following the floor-standing wall up (clockwise) into the concave corner
  // under the return, then west along the return: past its end the last
  // boundary point x_o is kept and rounded at the follow distance. Before,
  // the robot curved toward the assembly line it still remembered, followed
  // that and the hall's outer walls, and never reached the goal (45 m in 150 s).
  const NavRun r = runNav({"warehouse_return_end", kWarehouseReturn, {12.0, 7.0}, {}, 9000});
  ASSERT_TRUE(r.reached);
  EXPECT_LT(r.path_m, 25.0);
  // It went over the return (north of y = 6 between x 6.8 and 8), not round the hall.
  bool over_the_return = false;
  double min_x_after_return = 1e9;
  for (const auto& p : r.poses) {
    if (p.x_m > 6.8 && p.x_m < 8.0 && p.y_m > 6.0) over_the_return = true;
    if (over_the_return) min_x_after_return = std::min(min_x_after_return, p.x_m);
  }
  EXPECT_TRUE(over_the_return);
  EXPECT_GT(min_x_after_return, 5.0);
  EXPECT_GT(r.min_gap_m, kNoCollisionGap);
}
