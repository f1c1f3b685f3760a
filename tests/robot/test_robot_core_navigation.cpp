// RobotCore running Command.go_to: goals and routes reached and acknowledged,
// refusals, and the safety stops that end navigation. The core is driven
// through onCommand/onSensorFrame by a kinematic robot that integrates the
// commanded wheel speeds into wheel travel AND heading (the core's odometry
// takes its heading from the frame), in free space (no echoes) or with a
// person's echoes (Eq 9). Also the robot's map for people tracking.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "shared/robot/robot_core.hpp"
#include "shared/world/robot_map.hpp"
#include "shared/behavior/human_awareness.hpp"
#include "shared/world/world.hpp"
#include "tests/support/paths.hpp"

using namespace inspect;
using robot::RobotCore;

namespace {

constexpr double kFrameDt_s = 0.01;

v1::Command goTo(uint64_t id, const std::vector<std::pair<double, double>>& points, double speed = 0.0,
                 const std::string& name = "") {
  v1::Command c;
  c.set_id(id);
  auto* g = c.mutable_go_to();
  for (const auto& [x, y] : points) {
    auto* p = g->add_points();
    p->set_x_m(x);
    p->set_y_m(y);
  }
  g->set_speed_m_s(speed);
  g->set_name(name);
  return c;
}

// A command without parameters: Stop, EStop, Resume, or a zero Teleop.
v1::Command bare(uint64_t id, v1::Command::KindCase kind) {
  v1::Command c;
  c.set_id(id);
  switch (kind) {
    case v1::Command::kStop: c.mutable_stop(); break;
    case v1::Command::kEstop: c.mutable_estop(); break;
    case v1::Command::kResume: c.mutable_resume(); break;
    case v1::Command::kTeleop: c.mutable_teleop(); break;
    default: break;
  }
  return c;
}

// An ideal differential-drive robot at 100 Hz: the wheels turn at the
// commanded speed (0 when the drive is disabled), the frame reports wheel
// travel and the integrated heading.
config::RobotConfig withGas(bool on) {
  config::RobotConfig r;
  if (on) r.gas = config::defaultGasConfig();
  return r;
}

struct KinematicRobot {
  config::RobotConfig robot;
  robot::SafetyParams safety;
  RobotCore core{robot, safety};
  serial::SensorFrame f;
  double t = 0.0;
  double x = 0.0, y = 0.0, theta = 0.0;  // true pose
  double disp_l = 0.0, disp_r = 0.0;
  serial::WheelCommand last;
  std::vector<v1::Ack> acks;
  std::vector<robot::CoreEvent> events;

  std::array<double, 4> gas{0.0, 0.0, 0.0, 20.9};  // values in the default channels' units
  int frames = 0;

  explicit KinematicRobot(const robot::SafetyParams& s = {}, bool with_gas = false)
      : robot(withGas(with_gas)), safety(s) {
    f.ultrasonic_mm = {serial::kNoEcho, serial::kNoEcho, serial::kNoEcho, serial::kNoEcho};
    core.onSerialState(true, 0.0);
    core.onLinkUp(0.0);
  }
  void step() {
    t += kFrameDt_s;
    core.onLinkActivity(t);
    const double enable = (last.flags & serial::WheelCommand::kEnable) ? 1.0 : 0.0;
    const double r = robot.geometry.wheel_radius_m;
    const double dl = enable * last.left_mrad_s * 1e-3 * r * kFrameDt_s;
    const double dr = enable * last.right_mrad_s * 1e-3 * r * kFrameDt_s;
    const double ds = (dl + dr) / 2.0, dth = (dr - dl) / robot.geometry.track_m;
    x += ds * std::cos(theta + dth / 2.0);
    y += ds * std::sin(theta + dth / 2.0);
    theta = control::wrapAngle(theta + dth);
    disp_l += dl;
    disp_r += dr;
    f.mcu_time_ms = static_cast<uint32_t>(std::lround(t * 1000));
    f.wheel_disp_0p1mm = {static_cast<int32_t>(std::lround(disp_l * 1e4)),
                          static_cast<int32_t>(std::lround(disp_r * 1e4))};
    f.wheel_speed_mrad_s = {static_cast<int16_t>(enable * last.left_mrad_s),
                            static_cast<int16_t>(enable * last.right_mrad_s)};
    f.heading_0p1mrad = static_cast<int16_t>(std::lround(theta * 1e4));
    // Gas readings with a count of wobble (a live sensor never reads the same for long).
    for (std::size_t i = 0; i < robot.gas.channels.size(); ++i)
      f.gas_raw[i] = std::isnan(gas[i]) ? config::kGasNoData
                                        : static_cast<uint16_t>(std::lround(gas[i] / robot.gas.channels[i].scale) +
                                                                (frames % 2));
    ++frames;
    last = core.onSensorFrame(f, t);
    for (auto& a : core.takeAcks()) acks.push_back(a);
    for (auto& e : core.takeEvents()) events.push_back(e);
  }
  void run(double seconds) {
    const int n = static_cast<int>(std::lround(seconds / kFrameDt_s));
    for (int i = 0; i < n; ++i) step();
  }
  // Runs until an Ack arrives or `max_s` passes; true if one did.
  bool runUntilAck(double max_s) {
    const std::size_t before = acks.size();
    for (double s = 0; s < max_s && acks.size() == before; s += kFrameDt_s) step();
    return acks.size() > before;
  }
  double distanceTo(double gx, double gy) const { return std::hypot(gx - x, gy - y); }
  v1::Telemetry telemetry() const {
    v1::Telemetry tl;
    core.fillTelemetry(tl, t);
    return tl;
  }
  int countEvents(const std::string& text) const {
    int n = 0;
    for (const auto& e : events) n += e.kind == v1::Event::INFO && e.text.find(text) != std::string::npos;
    return n;
  }
};

}  // namespace

TEST(RobotCoreNavigation, GotoInFreeSpaceReachesTheGoalAndAcksCompleted) {
  KinematicRobot r;
  r.run(0.05);
  const auto ack = r.core.onCommand(goTo(1, {{2.0, 1.0}}), r.t);
  ASSERT_EQ(ack.status(), v1::Ack::ACCEPTED) << ack.reason();
  EXPECT_EQ(r.core.mode(), v1::NAVIGATING);
  ASSERT_TRUE(r.runUntilAck(30.0));
  EXPECT_EQ(r.acks.back().command_id(), 1u);
  EXPECT_EQ(r.acks.back().status(), v1::Ack::COMPLETED);
  EXPECT_EQ(r.core.mode(), v1::IDLE);
  EXPECT_EQ(r.countEvents("goal 1/1 (2.00, 1.00) reached at"), 1);
  // The wheels ramp down (slew-limited) and the robot stays put near the goal.
  r.run(1.0);
  EXPECT_EQ(r.last.left_mrad_s, 0);
  EXPECT_EQ(r.last.right_mrad_s, 0);
  std::printf("goto (2, 1): final error %.3f m (odometry %.3f m) at t = %.2f s\n", r.distanceTo(2.0, 1.0),
              std::hypot(2.0 - r.core.pose().x_m, 1.0 - r.core.pose().y_m), r.t);
  EXPECT_LT(r.distanceTo(2.0, 1.0), 0.15);
  EXPECT_EQ(r.acks.size(), 1u) << "one COMPLETED, nothing more";
}

TEST(RobotCoreNavigation, RouteOfThreePointsVisitsEachInOrderAndCompletes) {
  KinematicRobot r;
  r.run(0.05);
  const std::vector<std::pair<double, double>> pts = {{1.5, 0.0}, {1.5, 1.5}, {0.0, 1.5}};
  ASSERT_EQ(r.core.onCommand(goTo(5, pts, 0.4, "square"), r.t).status(), v1::Ack::ACCEPTED);
  std::vector<double> closest(pts.size(), std::numeric_limits<double>::infinity());
  for (int k = 0; k < 6000 && r.acks.empty(); ++k) {
    r.step();
    for (std::size_t i = 0; i < pts.size(); ++i)
      closest[i] = std::min(closest[i], r.distanceTo(pts[i].first, pts[i].second));
  }
  ASSERT_EQ(r.acks.size(), 1u);
  EXPECT_EQ(r.acks[0].command_id(), 5u);
  EXPECT_EQ(r.acks[0].status(), v1::Ack::COMPLETED);
  EXPECT_EQ(r.core.mode(), v1::IDLE);
  for (std::size_t i = 0; i < pts.size(); ++i) EXPECT_LT(closest[i], 0.15) << "point " << i;
  // One event per goal, in order.
  std::vector<std::string> reached;
  for (const auto& e : r.events)
    if (e.text.find(" reached at ") != std::string::npos) reached.push_back(e.text.substr(0, 8));
  EXPECT_EQ(reached, (std::vector<std::string>{"goal 1/3", "goal 2/3", "goal 3/3"}));
  r.run(1.0);
  EXPECT_LT(r.distanceTo(0.0, 1.5), 0.15);
  const auto tl = r.telemetry();
  EXPECT_EQ(tl.goal_index(), 3u) << "every goal reached";
  EXPECT_EQ(tl.goal_count(), 3u);
  EXPECT_EQ(tl.nav_mode(), "");
  EXPECT_EQ(tl.nav_switches(), 3u) << "GO_TO_GOAL -> AT_GOAL once per goal in free space";
}

TEST(RobotCoreNavigation, TelemetryShowsTheAutomatonWhileNavigating) {
  KinematicRobot r;
  r.run(0.05);
  ASSERT_EQ(r.core.onCommand(goTo(1, {{3.0, 0.0}, {3.0, 2.0}}), r.t).status(), v1::Ack::ACCEPTED);
  r.run(1.0);
  auto tl = r.telemetry();
  EXPECT_EQ(tl.mode(), v1::NAVIGATING);
  EXPECT_EQ(tl.nav_mode(), "GO_TO_GOAL");
  EXPECT_EQ(tl.goal_index(), 0u);
  EXPECT_EQ(tl.goal_count(), 2u);
  EXPECT_EQ(tl.nav_switches(), 0u);
  EXPECT_NEAR(tl.goal_distance_m(), 3.0 - r.core.pose().x_m, 0.01);
  EXPECT_LT(tl.goal_distance_m(), 3.0);
  EXPECT_GT(tl.cmd_v_m_s(), 0.2);
  EXPECT_LE(tl.cmd_v_m_s(), 0.5 + 1e-9) << "default cruise speed";
  EXPECT_DOUBLE_EQ(tl.speed_factor(), 1.0) << "no awareness: Eq 9 factor 1";
  ASSERT_TRUE(r.runUntilAck(40.0));
  tl = r.telemetry();
  EXPECT_EQ(tl.mode(), v1::IDLE);
  EXPECT_EQ(tl.nav_mode(), "");
  EXPECT_EQ(tl.goal_index(), 2u);
  EXPECT_LT(tl.goal_distance_m(), 0.1);
}

TEST(RobotCoreNavigation, SpeedIsTheCommandsAndWheelsAreSlewed) {
  KinematicRobot r;
  r.run(0.05);
  ASSERT_EQ(r.core.onCommand(goTo(1, {{5.0, 0.0}}, 0.3), r.t).status(), v1::Ack::ACCEPTED);
  r.step();
  // 10 rad/s^2 * 10 ms: the first tick moves each wheel by at most 0.1 rad/s.
  EXPECT_LE(std::abs(r.last.left_mrad_s), 100);
  EXPECT_LE(std::abs(r.last.right_mrad_s), 100);
  r.run(2.0);
  EXPECT_NEAR(r.core.commandedTwist().v_m_s, 0.3, 0.01);
}

struct Rejection {
  const char* name;
  v1::Command cmd;
  const char* reason;  // part of the Ack's reason
};

TEST(RobotCoreNavigation, BadOrUntimelyGotoIsRejectedWithAReason) {
  std::vector<std::pair<double, double>> many(101, {1.0, 1.0});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Rejection> cases = {
      {"no points", goTo(1, {}), "no goal"},
      {"101 points", goTo(2, many), "at most 100"},
      {"NaN x", goTo(3, {{1.0, 1.0}, {nan, 0.0}}), "goal 2 has a non-finite"},
      {"infinite y", goTo(4, {{1.0, std::numeric_limits<double>::infinity()}}), "non-finite"},
      {"too fast", goTo(5, {{1.0, 0.0}}, 1.5), "above the robot's limit of 1.00 m/s"},
      {"negative speed", goTo(6, {{1.0, 0.0}}, -0.2), "speed must be"},
      {"NaN speed", goTo(7, {{1.0, 0.0}}, nan), "speed must be"},
  };
  KinematicRobot r;
  r.run(0.05);
  for (const auto& c : cases) {
    const auto ack = r.core.onCommand(c.cmd, r.t);
    EXPECT_EQ(ack.status(), v1::Ack::REJECTED) << c.name;
    EXPECT_NE(ack.reason().find(c.reason), std::string::npos) << c.name << ": " << ack.reason();
    EXPECT_EQ(r.core.mode(), v1::IDLE) << c.name;
  }
  // 100 points is the limit, not above it.
  std::vector<std::pair<double, double>> hundred(100, {1.0, 1.0});
  EXPECT_EQ(r.core.onCommand(goTo(8, hundred), r.t).status(), v1::Ack::ACCEPTED);
}

TEST(RobotCoreNavigation, GotoIsRefusedWithoutAPoseOrWhileLatched) {
  KinematicRobot fresh;
  const auto no_frame = fresh.core.onCommand(goTo(1, {{1.0, 0.0}}), 0.0);
  EXPECT_EQ(no_frame.status(), v1::Ack::REJECTED);
  EXPECT_NE(no_frame.reason().find("no sensor frame"), std::string::npos);

  KinematicRobot r;
  r.run(0.05);
  r.core.onCommand(bare(2, v1::Command::kEstop), r.t);
  const auto latched = r.core.onCommand(goTo(3, {{1.0, 0.0}}), r.t);
  EXPECT_EQ(latched.status(), v1::Ack::REJECTED);
  EXPECT_NE(latched.reason().find("e-stop latched"), std::string::npos);
  r.core.onSerialState(false, r.t);
  r.core.onCommand(bare(4, v1::Command::kResume), r.t);
  EXPECT_EQ(r.core.onCommand(goTo(5, {{1.0, 0.0}}), r.t).reason(), "e-stop latched: resume first")
      << "resume refused while the serial line is down";
}

TEST(RobotCoreNavigation, EstopDuringNavigationStopsAtOnceAndNeedsResume) {
  KinematicRobot r;
  r.run(0.05);
  ASSERT_EQ(r.core.onCommand(goTo(1, {{5.0, 0.0}}), r.t).status(), v1::Ack::ACCEPTED);
  r.run(1.5);
  ASSERT_GT(r.core.commandedTwist().v_m_s, 0.3);
  ASSERT_EQ(r.core.onCommand(bare(2, v1::Command::kEstop), r.t).status(), v1::Ack::ACCEPTED);
  EXPECT_EQ(r.core.mode(), v1::ESTOP);
  // The command sent at once after the e-stop brakes: zero and drive disabled, no ramp.
  r.last = r.core.commandNow();
  EXPECT_EQ(r.last.left_mrad_s, 0);
  EXPECT_EQ(r.last.right_mrad_s, 0);
  EXPECT_EQ(r.last.flags, 0);
  const double x_stop = r.x;
  r.run(2.0);
  EXPECT_EQ(r.core.mode(), v1::ESTOP);
  EXPECT_DOUBLE_EQ(r.x, x_stop);
  EXPECT_EQ(r.core.onCommand(goTo(3, {{5.0, 0.0}}), r.t).status(), v1::Ack::REJECTED);
  ASSERT_EQ(r.core.onCommand(bare(4, v1::Command::kResume), r.t).status(), v1::Ack::ACCEPTED);
  EXPECT_EQ(r.core.mode(), v1::IDLE) << "resume does not restart the route";
  r.run(1.0);
  EXPECT_DOUBLE_EQ(r.x, x_stop);
  EXPECT_TRUE(r.acks.empty()) << "an ended route is never COMPLETED";
  ASSERT_EQ(r.core.onCommand(goTo(5, {{5.0, 0.0}}), r.t).status(), v1::Ack::ACCEPTED);
  ASSERT_TRUE(r.runUntilAck(30.0));
  EXPECT_EQ(r.acks.back().command_id(), 5u);
  EXPECT_LT(r.distanceTo(5.0, 0.0), 0.15);
}

TEST(RobotCoreNavigation, StopAndTeleopEndNavigation) {
  KinematicRobot r;
  r.run(0.05);
  ASSERT_EQ(r.core.onCommand(goTo(1, {{5.0, 0.0}}), r.t).status(), v1::Ack::ACCEPTED);
  r.run(1.0);
  r.core.onCommand(bare(2, v1::Command::kStop), r.t);
  EXPECT_EQ(r.core.mode(), v1::IDLE);
  r.run(1.0);
  EXPECT_EQ(r.last.left_mrad_s, 0) << "a normal stop ramps down within a second";
  ASSERT_EQ(r.core.onCommand(goTo(3, {{5.0, 0.0}}), r.t).status(), v1::Ack::ACCEPTED);
  r.run(0.5);
  ASSERT_EQ(r.core.onCommand(bare(4, v1::Command::kTeleop), r.t).status(), v1::Ack::ACCEPTED);
  EXPECT_EQ(r.core.mode(), v1::TELEOP);
  EXPECT_EQ(r.telemetry().nav_mode(), "");
  r.run(0.2);
  EXPECT_TRUE(r.acks.empty());
  EXPECT_EQ(r.core.mode(), v1::TELEOP);
}

TEST(RobotCoreNavigation, StaleSensorFramesLatchFailsafe) {
  KinematicRobot r;
  r.run(0.05);
  ASSERT_EQ(r.core.onCommand(goTo(1, {{5.0, 0.0}}), r.t).status(), v1::Ack::ACCEPTED);
  r.run(1.0);
  std::optional<serial::WheelCommand> c;
  double t = r.t;
  for (int i = 0; i < 20 && !c; ++i) {
    t += 0.01;
    r.core.onLinkActivity(t);
    c = r.core.onTimer(t);
  }
  ASSERT_TRUE(c.has_value());
  EXPECT_LE(t - r.t, 0.111);
  EXPECT_EQ(c->left_mrad_s, 0);
  EXPECT_EQ(c->right_mrad_s, 0);
  EXPECT_EQ(r.core.mode(), v1::FAILSAFE);
  const auto again = r.core.onCommand(goTo(2, {{5.0, 0.0}}), t);
  EXPECT_EQ(again.status(), v1::Ack::REJECTED);
  EXPECT_NE(again.reason().find("failsafe latched"), std::string::npos) << again.reason();
}

TEST(RobotCoreNavigation, LinkLossDuringNavigationLatchesFailsafe) {
  KinematicRobot r;
  r.run(0.05);
  ASSERT_EQ(r.core.onCommand(goTo(1, {{5.0, 0.0}}), r.t).status(), v1::Ack::ACCEPTED);
  r.run(0.5);
  r.core.onLinkDown(r.t, "closed");
  EXPECT_EQ(r.core.mode(), v1::FAILSAFE);
  EXPECT_EQ(r.core.commandNow().left_mrad_s, 0);
}

TEST(RobotCoreNavigation, PeopleSlowAndStopTheRobotOnItsWayEq9) {
  KinematicRobot r;
  behavior::AwarenessConfig acfg;
  r.core.setAwareness(std::make_unique<behavior::HumanAwareness>(
      r.robot.ultrasonic, acfg,
      behavior::loadSpeedStrategy(inspect::test::srcPath("config/fuzzy/speed_strategy.fis"), acfg.speed)));
  r.run(0.05);
  ASSERT_EQ(r.core.onCommand(goTo(1, {{10.0, 0.0}}), r.t).status(), v1::Ack::ACCEPTED);
  // A person (0.25 m radius) walks straight at the robot at 0.6 m/s from 5 m
  // ahead; both front sensors (0.30 m ahead of the axle) hear them.
  const double t0 = r.t;
  double t_slow = -1, t_stop = -1;
  double worst_excess = 0, nav_w_stopped = 0;
  for (int k = 0; k < 1000 && (t_stop < 0 || r.t < t_stop + 1.0); ++k) {
    const double person_x = 5.0 - 0.6 * (r.t - t0);
    const double range_m = person_x - r.x - 0.25 - 0.30;
    const uint16_t mm = range_m > 0.02 && range_m < 4.5 ? static_cast<uint16_t>(std::lround(range_m * 1000)) : serial::kNoEcho;
    r.f.ultrasonic_mm = {mm, mm, serial::kNoEcho, serial::kNoEcho};
    r.step();
    const auto tl = r.telemetry();
    if (t_slow < 0 && tl.speed_factor() < 1.0) t_slow = r.t;
    if (t_stop < 0 && tl.speed_factor() == 0.0) t_stop = r.t;
    // Eq 9 scales the navigation speed (0.5 m/s at most); the wheel slew may lag by one step.
    worst_excess = std::max(worst_excess, tl.cmd_v_m_s() - (tl.speed_factor() * 0.5 + 0.021));
    // What the automaton asks for while the factor holds the robot (it turns away from the person).
    if (tl.speed_factor() == 0.0) nav_w_stopped = std::max(nav_w_stopped, std::abs(r.core.navigator()->output().twist.w_rad_s));
  }
  ASSERT_GT(t_slow, 0.0) << "the person slowed the robot";
  ASSERT_GT(t_stop, 0.0) << "and stopped it";
  std::printf("Eq 9 on navigation: slowed %.2f s, stopped %.2f s after the start; automaton's |w| up to %.2f rad/s\n",
              t_slow - t0, t_stop - t0, nav_w_stopped);
  EXPECT_LE(worst_excess, 0.0);
  EXPECT_EQ(r.core.mode(), v1::NAVIGATING) << "a person pauses the route, does not end it";
  EXPECT_EQ(r.core.commandedTwist().v_m_s, 0.0);
  EXPECT_GT(nav_w_stopped, 0.1) << "the automaton wanted to turn meanwhile";
  EXPECT_EQ(r.core.commandedTwist().w_rad_s, 0.0) << "factor 0 stops the turn too";
}

// --- the robot's map for people tracking (robot_client --map) ---

TEST(RobotMap, WallsAndObstacleEdgesMoveIntoTheOdometryFrame) {
  // Start at (2, 4) facing +y: odometry x = world +y, odometry y = world -x.
  const world::World w = world::loadWorldText(R"(name: map_test
start: {x_m: 2.0, y_m: 4.0, theta_rad: 1.5707963267948966}
walls:
  - {from_m: [2.0, 6.0], to_m: [4.0, 6.0]}
obstacles:
  - vertices_m: [1.0, 5.0,  1.5, 5.0,  1.5, 5.5]
)",
                                          "map_test.yaml");
  const auto map = world::mapFromWorld(w);
  ASSERT_EQ(map.size(), 4u) << "one wall and three obstacle edges";
  EXPECT_NEAR(map[0].a.x, 2.0, 1e-12);
  EXPECT_NEAR(map[0].a.y, 0.0, 1e-12);
  EXPECT_NEAR(map[0].b.x, 2.0, 1e-12);
  EXPECT_NEAR(map[0].b.y, -2.0, 1e-12);
  // Every edge keeps its length, and the obstacle's first vertex (1, 5) is at odometry (1, 1).
  bool corner = false;
  for (const auto& m : map) {
    corner = corner || (std::abs(m.a.x - 1.0) < 1e-12 && std::abs(m.a.y - 1.0) < 1e-12);
    EXPECT_GT(std::hypot(m.b.x - m.a.x, m.b.y - m.a.y), 0.49);
  }
  EXPECT_TRUE(corner);
  // The start pose itself is the odometry origin: an empty world gives an empty map.
  EXPECT_TRUE(world::mapFromWorld(world::loadWorldText("name: empty\n", "empty.yaml")).empty());
}

TEST(RobotCoreNavigation, AGoalWithoutProgressIsGivenUpWithFailed) {
  robot::SafetyParams safety;
  safety.nav_stall_s = 3.0;
  KinematicRobot r(safety);
  r.run(0.05);
  // Boxed in: every sonar hears something 0.3 m away wherever the robot turns.
  r.f.ultrasonic_mm = {300, 300, 300, 300};
  ASSERT_EQ(r.core.onCommand(goTo(5, {{4.0, 0.0}}), r.t).status(), v1::Ack::ACCEPTED);
  ASSERT_TRUE(r.runUntilAck(20.0));
  const v1::Ack& a = r.acks.back();
  EXPECT_EQ(a.command_id(), 5u);
  EXPECT_EQ(a.status(), v1::Ack::FAILED);
  EXPECT_NE(a.reason().find("no progress for 3 s"), std::string::npos) << a.reason();
  EXPECT_EQ(r.core.mode(), v1::IDLE);
  EXPECT_GE(r.t, 3.0);
  EXPECT_LT(r.t, 6.0);
  EXPECT_EQ(r.countEvents("not reached"), 1);
}

// ---- Gas: alarms on the robot, the reaction to a HIGH alarm, inspection points ----

namespace {

int countKind(const std::vector<robot::CoreEvent>& ev, v1::Event::Kind k, v1::GasAlarm::Level level) {
  int n = 0;
  for (const auto& e : ev) n += e.kind == k && e.gas_alarm && e.gas_alarm->level() == level;
  return n;
}

robot::SafetyParams reaction(const std::string& r) {
  robot::SafetyParams s;
  s.gas_reaction = *robot::gasReactionOf(r);
  return s;
}

}  // namespace

TEST(RobotCoreGas, AlarmsGoOutAsEventsWithPoseAndAreListedInTelemetry) {
  KinematicRobot r({}, true);
  r.run(1.0);
  EXPECT_TRUE(r.events.empty());
  auto tl = r.telemetry();
  ASSERT_EQ(tl.gas_size(), 4);
  EXPECT_NEAR(tl.gas(0), 0.0, 0.011);
  EXPECT_NEAR(tl.gas(3), 20.9, 0.011);
  EXPECT_EQ(tl.active_alarms_size(), 0);
  r.gas[1] = 12.0;  // H2S above A1 5 and A2 10 ppm
  r.run(3.0);
  ASSERT_EQ(countKind(r.events, v1::Event::ALARM_RAISED, v1::GasAlarm::LOW), 1);
  ASSERT_EQ(countKind(r.events, v1::Event::ALARM_RAISED, v1::GasAlarm::HIGH), 1);
  for (const auto& e : r.events) {
    if (!e.gas_alarm) continue;
    EXPECT_EQ(e.gas_alarm->channel_name(), "H2S");
    EXPECT_EQ(e.gas_alarm->unit(), "ppm");
    EXPECT_TRUE(e.gas_alarm->active());
    EXPECT_TRUE(e.gas_alarm->has_pose());
    EXPECT_NE(e.text.find("H2S"), std::string::npos) << e.text;
  }
  tl = r.telemetry();
  EXPECT_EQ(tl.active_alarms_size(), 2);
  r.gas[1] = 0.0;
  r.run(4.0);
  EXPECT_EQ(countKind(r.events, v1::Event::ALARM_CLEARED, v1::GasAlarm::HIGH), 1);
  EXPECT_EQ(countKind(r.events, v1::Event::ALARM_CLEARED, v1::GasAlarm::LOW), 1);
  EXPECT_EQ(r.telemetry().active_alarms_size(), 0);
  // The channels as announced in Hello.
  const auto ch = r.core.gasChannels();
  ASSERT_EQ(ch.size(), 4u);
  EXPECT_EQ(ch[3].name(), "O2");
  EXPECT_TRUE(ch[3].falling());
}

TEST(RobotCoreGas, NoDataReadsAsNaNAndRaisesASensorFault) {
  KinematicRobot r({}, true);
  r.run(0.5);
  r.gas[2] = std::numeric_limits<double>::quiet_NaN();  // CO sends 0xFFFF
  r.run(0.3);
  EXPECT_EQ(countKind(r.events, v1::Event::ALARM_RAISED, v1::GasAlarm::SENSOR_FAULT), 0) << "0.5 s grace";
  r.run(0.3);
  auto tl = r.telemetry();
  ASSERT_EQ(countKind(r.events, v1::Event::ALARM_RAISED, v1::GasAlarm::SENSOR_FAULT), 1);
  for (const auto& e : r.events)
    if (e.gas_alarm) {
      EXPECT_EQ(e.gas_alarm->fault(), "no_data");
    }
  EXPECT_TRUE(std::isnan(tl.gas(2)));
}

TEST(RobotCoreGas, HighAlarmOnARouteStopsAndHoldsUntilResume) {
  KinematicRobot r(reaction("stop"), true);
  r.run(0.05);
  ASSERT_EQ(r.core.onCommand(goTo(1, {{6.0, 0.0}}, 0.5), r.t).status(), v1::Ack::ACCEPTED);
  r.run(3.0);
  r.gas[0] = 30.0;  // CH4 above A2 20 %LEL
  r.run(4.0);
  EXPECT_EQ(r.countEvents("stopped and holding"), 1);
  const double x_hold = r.x;
  r.run(5.0);
  EXPECT_NEAR(r.x, x_hold, 0.01) << "holding";
  auto tl = r.telemetry();
  EXPECT_EQ(tl.mode(), v1::NAVIGATING);
  EXPECT_EQ(tl.nav_mode(), "GAS_HOLD");
  EXPECT_TRUE(r.acks.empty());
  r.gas[0] = 0.0;
  r.run(3.0);
  EXPECT_NEAR(r.x, x_hold, 0.01) << "the alarm clearing does not restart the robot";
  ASSERT_EQ(r.core.onCommand(bare(2, v1::Command::kResume), r.t).status(), v1::Ack::ACCEPTED);
  ASSERT_TRUE(r.runUntilAck(30.0));
  EXPECT_EQ(r.acks.back().status(), v1::Ack::COMPLETED);
  EXPECT_LT(r.distanceTo(6.0, 0.0), 0.15);
}

TEST(RobotCoreGas, HighAlarmWithContinueKeepsGoing) {
  KinematicRobot r(reaction("continue"), true);
  r.run(0.05);
  ASSERT_EQ(r.core.onCommand(goTo(1, {{4.0, 0.0}}, 0.5), r.t).status(), v1::Ack::ACCEPTED);
  r.run(2.0);
  r.gas[0] = 30.0;
  ASSERT_TRUE(r.runUntilAck(30.0));
  EXPECT_EQ(r.acks.back().status(), v1::Ack::COMPLETED);
  EXPECT_EQ(r.countEvents("route continues"), 1);
}

TEST(RobotCoreGas, HighAlarmWithRetreatGoesBackAlongTheRoute) {
  KinematicRobot r(reaction("retreat"), true);
  r.run(0.05);
  ASSERT_EQ(r.core.onCommand(goTo(1, {{3.0, 0.0}, {3.0, 2.0}, {0.0, 2.0}}, 0.5), r.t).status(),
            v1::Ack::ACCEPTED);
  // Past the first point and on the way to the second.
  for (int k = 0; k < 4000 && r.telemetry().goal_index() < 1; ++k) r.step();
  r.run(1.0);
  ASSERT_EQ(r.telemetry().goal_index(), 1u);
  r.gas[0] = 30.0;
  r.run(3.0);
  EXPECT_EQ(r.countEvents("retreating along the route"), 1);
  EXPECT_EQ(r.telemetry().nav_mode(), "RETREAT");
  double closest_first = 1e9;
  for (int k = 0; k < 6000 && r.acks.empty(); ++k) {
    r.step();
    closest_first = std::min(closest_first, r.distanceTo(3.0, 0.0));
  }
  ASSERT_EQ(r.acks.size(), 1u);
  EXPECT_EQ(r.acks[0].status(), v1::Ack::FAILED);
  EXPECT_NE(r.acks[0].reason().find("retreated to the route's start after CH4 HIGH alarm"), std::string::npos)
      << r.acks[0].reason();
  EXPECT_LT(closest_first, 0.15) << "back through the point already reached";
  EXPECT_LT(r.distanceTo(0.0, 0.0), 0.15);
  EXPECT_EQ(r.core.mode(), v1::IDLE);
}

TEST(RobotCoreGas, InspectionPointsDwellAndPointTheCamera) {
  KinematicRobot plain;
  plain.run(0.05);
  ASSERT_EQ(plain.core.onCommand(goTo(1, {{2.0, 0.0}, {2.0, 1.5}}, 0.5), plain.t).status(), v1::Ack::ACCEPTED);
  ASSERT_TRUE(plain.runUntilAck(40.0));
  const double t_plain = plain.t;

  KinematicRobot r;
  r.run(0.05);
  auto cmd = goTo(1, {{2.0, 0.0}, {2.0, 1.5}}, 0.5, "tour");
  cmd.mutable_go_to()->set_inspection(true);
  auto* p0 = cmd.mutable_go_to()->mutable_points(0);
  p0->set_dwell_s(4.0);
  p0->set_label("valve_A");
  p0->mutable_ptz()->set_pan_rad(M_PI / 2);
  p0->mutable_ptz()->set_tilt_rad(-0.2);
  auto* p1 = cmd.mutable_go_to()->mutable_points(1);
  p1->set_dwell_s(2.0);
  ASSERT_EQ(r.core.onCommand(cmd, r.t).status(), v1::Ack::ACCEPTED);
  EXPECT_EQ(r.telemetry().waypoint_label(), "valve_A");
  bool saw_dwell = false;
  double max_dwell_left = 0.0;
  std::vector<v1::Ptz> ptz;
  for (int k = 0; k < 6000 && r.acks.empty(); ++k) {
    r.step();
    for (auto& x : r.core.takePtz()) ptz.push_back(x);
    const auto tl = r.telemetry();
    if (tl.nav_mode() == "DWELL") {
      saw_dwell = true;
      max_dwell_left = std::max(max_dwell_left, tl.dwell_remaining_s());
      EXPECT_LE(std::hypot(tl.cmd_v_m_s(), 0.0), 0.3);
    }
  }
  ASSERT_EQ(r.acks.size(), 1u);
  EXPECT_EQ(r.acks[0].status(), v1::Ack::COMPLETED);
  EXPECT_TRUE(saw_dwell);
  EXPECT_NEAR(max_dwell_left, 4.0, 0.05);
  ASSERT_EQ(ptz.size(), 1u);
  EXPECT_NEAR(ptz[0].pan_rad(), M_PI / 2, 1e-9);
  EXPECT_EQ(r.countEvents("inspection point 1/2 'valve_A': dwelling 4.0 s, camera pan 90 deg tilt -11 deg"), 1);
  EXPECT_EQ(r.countEvents("inspection point 2/2: dwelling 2.0 s"), 1);
  // Both dwells add to the time of the same route without them.
  EXPECT_NEAR(r.t - t_plain, 6.0, 0.6);
  EXPECT_LT(r.distanceTo(2.0, 1.5), 0.15);
}

TEST(RobotCoreGas, BadInspectionPointsAreRejected) {
  KinematicRobot r;
  r.run(0.05);
  auto cmd = goTo(1, {{2.0, 0.0}});
  cmd.mutable_go_to()->mutable_points(0)->set_dwell_s(-1.0);
  auto ack = r.core.onCommand(cmd, r.t);
  EXPECT_EQ(ack.status(), v1::Ack::REJECTED);
  EXPECT_NE(ack.reason().find("dwell_s"), std::string::npos);
  cmd = goTo(2, {{2.0, 0.0}});
  cmd.mutable_go_to()->mutable_points(0)->mutable_ptz()->set_tilt_rad(3.0);
  ack = r.core.onCommand(cmd, r.t);
  EXPECT_EQ(ack.status(), v1::Ack::REJECTED);
  EXPECT_NE(ack.reason().find("tilt"), std::string::npos);
}
