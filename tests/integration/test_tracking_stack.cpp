// The paper's circle experiment through the full stack (mcu_sim on a pty +
// robot_client + pc_server console) against the same experiment in-process.
#include <gtest/gtest.h>

#include <cstdio>
#include <sstream>

#include "shared/config/control_config.hpp"
#include "sim/closed_loop.hpp"
#include "tests/integration/stack.hpp"

using namespace inspect;
using namespace inspect::test;

namespace {
sim::ClosedLoopMetrics inProcess(control::WheelControl wc) {
  const auto robot = config::loadRobotConfigFile(srcPath("config/robot.yaml"));
  auto ctl = config::loadControlConfigFile(srcPath("config/control.yaml"));
  config::applyRobot(ctl, robot);
  sim::ClosedLoopConfig cfg;
  cfg.robot = robot;
  cfg.tracker = ctl.tracker;
  cfg.tracker.wheel_control = wc;
  return sim::runClosedLoop(cfg, control::makeCircle({0, 0, 0}, 3.5, 0.5), config::loadScheduler(ctl), false)
      .metrics;
}
}  // namespace

TEST(TrackingStack, CircleMatchesTheInProcessExperimentWithin20Percent) {
  const auto ref = inProcess(control::WheelControl::kFuzzyPid);
  std::ostringstream script;
  script << "expect robots >= 1 within 15\nexpect sensor_hz > 50 within 5\n"
         << "track circle 3.5 0.5 1 fuzzy_pid\nexpect mode == TRACKING within 1\n"
         << "expect mode == IDLE within 40\nexpect progress ~ 1 0.001\nstatus\n"
         << "expect max_pos_err ~ " << ref.max_pos_err_m << " " << 0.2 * ref.max_pos_err_m << "\n"
         << "expect max_ang_err ~ " << ref.max_ang_err_rad << " " << 0.2 * ref.max_ang_err_rad << "\n";
  Stack s("track");
  ASSERT_TRUE(s.startServer(script.str())) << s.logs();
  // 4x faster than real time: the client's loop runs on the MCU's clock (dt
  // from the frames), so the control is the same; only wall time shrinks.
  s.startRobot("robot1", "empty.yaml", {}, {"--rate", "4"});
  const auto rc = s.server().wait(90);
  ASSERT_TRUE(rc.has_value()) << s.logs();
  std::printf("TRACK in-process max position error %.4f m, max angle error %.4f rad\n%s", ref.max_pos_err_m,
              ref.max_ang_err_rad, s.serverOutput().c_str());
  EXPECT_EQ(*rc, 0) << s.logs();
}
