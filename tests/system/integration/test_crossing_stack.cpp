// The crossing scenario (paper Sec. 5.1.1) through the full stack: mcu_sim on a
// pty with the crossing world and a walking person, robot_client with the map
// and the fuzzy speed strategy, pc_server's console sending `track line`.
// The outcome must fall in the same class as the in-process scenario suite:
// completed, no contact, the robot stops for the person outside the intimate
// zone, and the closest approach is no closer than the in-process run's
// (less 0.3 m): one-sided, since keeping farther from the person is never wrong.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "experiments/scenarios/scenario.hpp"
#include "tests/support/stack.hpp"

using namespace inspect;
using namespace inspect::test;

namespace {

sim::RunMetrics inProcessCrossing() {
  const auto ctx = sim::loadScenarioContext(srcPath("config/robot.yaml"), srcPath("config/control.yaml"),
                                            srcPath("config/behavior.yaml"));
  for (const auto& s : sim::loadSuiteFile(srcPath("config/scenarios/suite.yaml")))
    if (s.name == "crossing") return sim::runScenario(s, ctx, {}).metrics;
  ADD_FAILURE() << "no crossing scenario in config/scenarios/suite.yaml";
  return {};
}

}  // namespace

TEST(CrossingStack, SameOutcomeClassAsInProcess) {
  const sim::RunMetrics ref = inProcessCrossing();
  ASSERT_TRUE(ref.success) << ref.failure;
  ASSERT_GE(ref.stop_s, 0.0) << "in-process: the robot never stopped for the person";

  Stack s("crossing");
  ASSERT_TRUE(s.startServer("expect robots >= 1 within 15\nexpect sensor_hz > 50 within 5\n"
                            "track line 9 0.5\nexpect mode == TRACKING within 1\n"
                            "expect mode == IDLE within 20\nexpect progress ~ 1 0.001\nstatus\n"))
      << s.logs();
  const std::string world = srcPath("config/worlds/crossing.yaml");
  auto& r = s.startRobot("robot1", "crossing.yaml", {}, {"--rate", "4", "--people-wait-motion"}, {"--map", world});
  const auto rc = s.server().wait(90);
  ASSERT_TRUE(rc.has_value()) << s.logs();
  EXPECT_EQ(*rc, 0) << s.logs();

  const Truth truth = readTruth(r.truth);
  ASSERT_FALSE(truth.rows.empty());
  ASSERT_FALSE(truth.people.empty()) << "no P rows: the person never appeared";
  for (const auto& e : truth.events) EXPECT_NE(e.name, "collision_person") << e.detail;
  for (const auto& e : truth.events) EXPECT_NE(e.name, "collision") << e.detail;
  double min_dist = 1e9;
  for (const auto& p : truth.people) min_dist = std::min(min_dist, p.robot_dist);
  // Stopped for the person: after moving, the true speed fell below 0.02 m/s
  // while the person was within the max avoidance distance (3 m).
  const auto robot = config::loadRobotConfigFile(srcPath("config/robot.yaml"));
  bool moved = false, stopped = false;
  for (const auto& row : truth.rows) {
    const double v = 0.5 * robot.geometry.wheel_radius_m * (row.wheel_l + row.wheel_r);
    if (std::abs(v) > 0.1) moved = true;
    if (moved && std::abs(v) < 0.02) {
      // Nearest P row in time.
      double best_dt = 1e9, d = 1e9;
      for (const auto& p : truth.people)
        if (std::abs(p.t - row.t) < best_dt) {
          best_dt = std::abs(p.t - row.t);
          d = p.robot_dist;
        }
      if (d < 3.0) stopped = true;
    }
  }
  std::printf("CROSSING full stack: min person distance %.2f m (in-process %.2f m), stopped for the person: %s\n",
              min_dist, ref.min_person_m, stopped ? "yes" : "no");
  EXPECT_TRUE(stopped);
  EXPECT_GT(min_dist, 0.45);                       // never in the intimate zone
  EXPECT_GE(min_dist, ref.min_person_m - 0.3);     // no closer than in-process, less 0.3 m
}
