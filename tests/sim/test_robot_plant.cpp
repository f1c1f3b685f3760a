// Robot plant in closed loop: motor lag, straight drive, spin in place, the
// sign convention, and walls that cannot be penetrated.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "shared/config/robot_config.hpp"
#include "sim/robot_plant.hpp"
#include "sim/simulation.hpp"
#include "tests/sim/world_text.hpp"

using namespace inspect;
using namespace inspect::sim;

namespace {

using inspect::test::worldOf;

constexpr double kDt_s = 0.001;

config::RobotConfig paperRobot() { return config::RobotConfig{}; }

PlantState run(const RobotPlant& p, PlantState s, control::WheelSpeeds sp, double t_s) {
  const int n = static_cast<int>(std::lround(t_s / kDt_s));
  for (int i = 0; i < n; ++i) s = p.step(s, sp, kDt_s).state;
  return s;
}

}  // namespace

TEST(RobotPlant, StepReaches63PercentAtOneTimeConstant) {
  const auto robot = paperRobot();
  const World w;
  const RobotPlant p(robot, w);
  const double tau = robot.motor.time_constant_s;
  const PlantState s = run(p, {}, {2.0, -3.0}, tau);
  EXPECT_NEAR(s.wheel.left_rad_s / 2.0, 1.0 - std::exp(-1.0), 0.01);
  EXPECT_NEAR(s.wheel.right_rad_s / -3.0, 1.0 - std::exp(-1.0), 0.01);
  const PlantState later = run(p, s, {2.0, -3.0}, 10 * tau);
  EXPECT_NEAR(later.wheel.left_rad_s, 2.0, 1e-3);
}

TEST(RobotPlant, SetpointClampedToWheelLimit) {
  const auto robot = paperRobot();
  const World w;
  const RobotPlant p(robot, w);
  const PlantState s = run(p, {}, {100.0, -100.0}, 20 * robot.motor.time_constant_s);
  EXPECT_NEAR(s.wheel.left_rad_s, robot.limits.max_wheel_speed_rad_s, 1e-6);
  EXPECT_NEAR(s.wheel.right_rad_s, -robot.limits.max_wheel_speed_rad_s, 1e-6);
  const PlantState n = run(p, {}, {std::nan(""), 1.0}, 1.0);
  EXPECT_EQ(n.wheel.left_rad_s, 0.0);
}

TEST(RobotPlant, StraightDriveTwoSecondsAtHalfMetrePerSecond) {
  const auto robot = paperRobot();
  const World w;
  const RobotPlant p(robot, w);
  const double wheel = 0.5 / robot.geometry.wheel_radius_m;
  const PlantState s = run(p, {}, {wheel, wheel}, 2.0);
  // A first-order lag of tau loses v * tau of distance once settled.
  const double expect = 0.5 * 2.0 - 0.5 * robot.motor.time_constant_s;
  EXPECT_NEAR(s.pose.x_m, expect, 1e-3);
  EXPECT_NEAR(s.pose.y_m, 0.0, 1e-9);
  EXPECT_NEAR(s.pose.theta_rad, 0.0, 1e-9);
  EXPECT_NEAR(s.wheel_travel_left_m, expect, 1e-3);
  EXPECT_NEAR(s.wheel_travel_right_m, expect, 1e-3);
}

TEST(RobotPlant, SpinInPlace) {
  const auto robot = paperRobot();
  const World w;
  const RobotPlant p(robot, w);
  // w = r (w_r - w_l) / L = 0.2 * 2 / 0.438 rad/s, CCW for the faster right wheel.
  const PlantState s = run(p, {}, {-1.0, 1.0}, 1.0);
  const double yaw_rate = robot.geometry.wheel_radius_m * 2.0 / robot.geometry.track_m;
  EXPECT_NEAR(s.pose.theta_rad, yaw_rate * (1.0 - robot.motor.time_constant_s), 2e-3);
  EXPECT_NEAR(s.pose.x_m, 0.0, 1e-9);
  EXPECT_NEAR(s.pose.y_m, 0.0, 1e-9);
}

TEST(RobotPlant, FasterRightWheelTurnsLeft) {
  const World w;
  const RobotPlant p(paperRobot(), w);
  const PlantState s = run(p, {}, {2.0, 3.0}, 1.0);
  EXPECT_GT(s.pose.theta_rad, 0.0);
  EXPECT_GT(s.pose.y_m, 0.0);
}

TEST(RobotPlant, QuarterCircleArc) {
  const auto robot = paperRobot();
  const World w;
  const RobotPlant p(robot, w);
  // Steady arc: v = 0.5 m/s, w = 0.5 rad/s -> radius 1 m; start settled on it.
  const auto ws = control::wheelsFromTwist({0.5, 0.5}, robot.geometry.wheel_radius_m, robot.geometry.track_m);
  PlantState s;
  s.wheel = ws;
  const double t_s = 3.141;  // about a quarter turn, a whole number of steps
  s = run(p, s, ws, t_s);
  const double th = 0.5 * t_s;
  EXPECT_NEAR(s.pose.theta_rad, th, 1e-9);
  EXPECT_NEAR(s.pose.x_m, std::sin(th), 1e-6);
  EXPECT_NEAR(s.pose.y_m, 1.0 - std::cos(th), 1e-6);
}

TEST(RobotPlant, WallBlocksPenetration) {
  const auto robot = paperRobot();
  const World w = worldOf("walls:\n  - {from_m: [1.0, -2], to_m: [1.0, 2]}\n", "w.yaml");
  const RobotPlant p(robot, w);
  const double wheel = 1.0 / robot.geometry.wheel_radius_m;
  PlantState s;
  int blocked_steps = 0;
  for (int i = 0; i < 3000; ++i) {
    const auto r = p.step(s, {wheel, wheel}, kDt_s);
    s = r.state;
    blocked_steps += r.blocked;
    ASSERT_GE(1.0 - s.pose.x_m, robot.geometry.body_radius_m) << "step " << i;
  }
  EXPECT_GT(blocked_steps, 1000);
  EXPECT_NEAR(s.pose.x_m, 1.0 - robot.geometry.body_radius_m, 2e-3);  // stopped within one step of contact
  EXPECT_GT(s.wheel.left_rad_s, 0.9 * wheel);                        // the wheels keep spinning (slip)
  // Backing away is allowed.
  const PlantState back = run(p, s, {-wheel, -wheel}, 1.0);
  EXPECT_LT(back.pose.x_m, s.pose.x_m - 0.3);
}

TEST(RobotPlant, ConcaveObstacleBlocksInsideTheNotch) {
  const auto robot = paperRobot();
  // U opening to -x; the robot drives into the 1.2 m wide notch and stops at its end.
  const World w = worldOf("obstacles:\n  - {vertices_m: [2,-1.6, 5,-1.6, 5,1.6, 2,1.6, 2,0.6, 4,0.6, 4,-0.6, 2,-0.6]}\n", "w.yaml");
  const RobotPlant p(robot, w);
  const double wheel = 0.8 / robot.geometry.wheel_radius_m;
  PlantState s;
  for (int i = 0; i < 8000; ++i) {
    s = p.step(s, {wheel, wheel}, kDt_s).state;
    ASSERT_GE(clearance(w, {s.pose.x_m, s.pose.y_m}), robot.geometry.body_radius_m);
  }
  EXPECT_NEAR(s.pose.x_m, 4.0 - robot.geometry.body_radius_m, 2e-3);
}

TEST(Simulation, CollisionEventLoggedOncePerContact) {
  struct Events : SimObserver {
    int collisions = 0;
    void onEvent(double, std::string_view e, std::string_view) override { collisions += e == "collision"; }
  } events;
  const auto robot = paperRobot();
  Simulation sim(robot, worldOf("walls:\n  - {from_m: [1.0, -2], to_m: [1.0, 2]}\n", "w.yaml"), 1, &events);
  // Drive into the wall with commands every 10 ms for 3 s, then back off, then again.
  serial::FrameEncoder enc;
  auto drive = [&](int16_t mrad_s, int ms) {
    for (int t = 0; t < ms; t += 10) {
      const auto f = enc.encode(serial::WheelCommand{mrad_s, mrad_s, serial::WheelCommand::kEnable});
      sim.receive(f.span());
      sim.advanceTo(sim.timeMs() + 10);
    }
  };
  drive(5000, 3000);
  EXPECT_EQ(events.collisions, 1);
  EXPECT_EQ(sim.collisions(), 1u);
  drive(-2500, 1000);
  drive(5000, 2000);
  EXPECT_EQ(events.collisions, 2);
}
