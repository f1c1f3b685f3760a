// Navigation through the full stack: the console's `goto` reaches robot_client
// (mcu_sim on a pty), the robot's navigation automaton drives to the goal and
// acknowledges COMPLETED; checked against the simulator's ground truth.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "tests/support/stack.hpp"

using namespace inspect::test;

TEST(NavigationStack, GotoInTheEmptyWorldCompletesAtTheGoal) {
  const std::string script =
      "expect robots >= 1 within 15\n"
      "expect sensor_hz > 50 within 5\n"
      "goto 2 0\n"
      "expect mode == NAVIGATING within 1\n"
      "expect nav_mode == GO_TO_GOAL within 1\n"
      "expect goal_count == 1\n"
      "expect mode == IDLE within 30\n"
      "expect goal_index == 1\n"
      "expect nav_switches == 1\n"
      "expect x ~ 2 0.2\n"
      "expect y ~ 0 0.2\n"
      "wait 0.5\n"
      "status\n";
  Stack s("nav");
  ASSERT_TRUE(s.startServer(script)) << s.logs();
  // 4x faster than real time: the loop runs on the MCU's clock, so the
  // control is the same; only wall time shrinks.
  auto& robot = s.startRobot("robot1", "empty.yaml", {}, {"--rate", "4"});
  const auto rc = s.server().wait(60);
  ASSERT_TRUE(rc.has_value()) << s.logs();
  const std::string out = s.serverOutput();
  std::printf("%s", out.c_str());
  EXPECT_EQ(*rc, 0) << s.logs();
  EXPECT_NE(out.find("robot1: goto accepted"), std::string::npos) << out;
  EXPECT_NE(out.find("INFO: goal 1/1 (2.00, 0.00) reached at"), std::string::npos) << out;
  EXPECT_NE(out.find("robot1: goto completed"), std::string::npos) << out;
  // Ground truth: the robot stands within 0.2 m of the goal (the world's start is the origin).
  const Truth truth = readTruth(robot.truth);
  ASSERT_FALSE(truth.rows.empty());
  const auto& last = truth.rows.back();
  const double err = std::hypot(last.x - 2.0, last.y);
  std::printf("NAV goto 2 0: true final pose (%.3f, %.3f), %.3f m from the goal\n", last.x, last.y, err);
  EXPECT_LT(err, 0.2);
}

// The example route (config/routes/warehouse_tour.yaml) in the square room,
// with the room given to robot_client as its people-tracking map (--map).
TEST(NavigationStack, ExampleRouteInTheSquareRoomWithTheMap) {
  const std::string script = "expect robots >= 1 within 15\n"
                             "expect sensor_hz > 50 within 5\n"
                             "route " + srcPath("config/routes/warehouse_tour.yaml") + "\n"
                             "expect mode == NAVIGATING within 1\n"
                             "expect mode == IDLE within 120\n"
                             "expect goal_index == 5\n"
                             "expect goal_count == 5\n"
                             "status\n";
  Stack s("nav_route");
  ASSERT_TRUE(s.startServer(script)) << s.logs();
  auto& robot = s.startRobot("robot1", "square_room.yaml", {}, {"--rate", "8"},
                             {"--map", srcPath("config/worlds/square_room.yaml")});
  const auto rc = s.server().wait(120);
  ASSERT_TRUE(rc.has_value()) << s.logs();
  const std::string out = s.serverOutput();
  std::printf("%s", out.c_str());
  EXPECT_EQ(*rc, 0) << s.logs();
  EXPECT_NE(readFile(s.dir() / "robot1-client.err").find("wall segments"), std::string::npos) << "map loaded";
  for (int i = 1; i <= 5; ++i)
    EXPECT_NE(out.find("INFO: goal " + std::to_string(i) + "/5 "), std::string::npos) << i;
  EXPECT_NE(out.find("robot1: route completed"), std::string::npos) << out;
  // The last point is the start: world (2, 4).
  const Truth truth = readTruth(robot.truth);
  ASSERT_FALSE(truth.rows.empty());
  const double err = std::hypot(truth.rows.back().x - 2.0, truth.rows.back().y - 4.0);
  std::printf("NAV route: back at the start within %.3f m (truth), %.1f s of simulated time\n", err,
              truth.rows.back().t);
  EXPECT_LT(err, 0.2);
}
