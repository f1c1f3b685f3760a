// The paper's circle experiment through the full stack (mcu_sim on a pty +
// robot_client + pc_server console) against the same experiment in-process.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <sstream>
#include <utility>
#include <vector>

#include "shared/config/control_config.hpp"
#include "sim/closed_loop.hpp"
#include "sim/robot_plant.hpp"
#include "tests/support/stack.hpp"

using namespace inspect;
using namespace inspect::test;

namespace {
// The in-process loop with the full stack's own latency as plant dead time:
// a wheel command is computed from a sensor frame and reaches the motors
// about one frame later (serial transmission, the client's tick, the MCU's
// next step). The paper's gains are sensitive to delay (docs/tuning.md).
sim::ClosedLoopMetrics inProcess(control::WheelControl wc, double dead_time_s, uint32_t seed) {
  const auto robot = config::loadRobotConfigFile(srcPath("config/robot.yaml"));
  auto ctl = config::loadControlConfigFile(srcPath("config/control.yaml"));
  config::applyRobot(ctl, robot);
  sim::ClosedLoopConfig cfg;
  cfg.robot = robot;
  cfg.plant = sim::nominalPlant(robot);
  cfg.plant->left.dead_time_s = cfg.plant->right.dead_time_s = dead_time_s;
  cfg.seed = seed;
  cfg.tracker = ctl.tracker;
  cfg.tracker.wheel_control = wc;
  return sim::runClosedLoop(cfg, control::makeCircle({0, 0, 0}, 3.5, 0.5), config::loadScheduler(ctl), false)
      .metrics;
}
}  // namespace

// The circle (radius 3.5 m at 0.5 m/s, fuzzy-PID) driven through a stack's
// console: its maximum position and angle errors (NaN when not printed).
// `firmware` non-empty: that QEMU image on the line (Stack::useFirmware).
std::pair<double, double> trackCircle(const char* tag, const std::vector<std::string>& sim_args,
                                      const std::string& firmware) {
  std::ostringstream script;
  script << "expect robots >= 1 within 15\nexpect sensor_hz > 50 within 5\n"
         << "track circle 3.5 0.5 1 fuzzy_pid\nexpect mode == TRACKING within 1\n"
         << "expect mode == IDLE within 80\nexpect progress ~ 1 0.001\nstatus\n"
         << "expect max_pos_err > 0\nexpect max_ang_err > 0\n";
  Stack s(firmware.empty() ? tag : std::string(tag) + "_fw");
  if (!firmware.empty()) s.useFirmware(firmware);
  EXPECT_TRUE(s.startServer(script.str())) << s.logs();
  // At --rate 2 the client's loop runs on the MCU's clock (dt from the frames),
  // so the control is the same; only wall time shrinks. The firmware: real time.
  s.startRobot("robot1", "empty.yaml", {}, sim_args);
  const auto rc = s.server().wait(120);
  EXPECT_TRUE(rc.has_value()) << s.logs();
  const std::string out = s.serverOutput();
  std::printf("%s", out.c_str());
  EXPECT_EQ(rc.value_or(-1), 0) << s.logs();
  const double pos = expectedValue(out, "max_pos_err"), ang = expectedValue(out, "max_ang_err");
  EXPECT_TRUE(std::isfinite(pos) && std::isfinite(ang)) << "the console printed no tracking figures\n" << out;
  return {pos, ang};
}
const char* s_emulator() { return "track"; }

TEST(TrackingStack, CircleTrackedNoWorseThanTheInProcessExperimentBy20Percent) {
  // The maxima are peaks of a lightly damped oscillation: they move with the
  // noise and with the link's latency (about 10 ms of wall time, 20 ms of
  // sim time at --rate 2; up to 30 ms when a shared machine schedules a
  // process late). The full stack must not track worse than 20 % above the
  // worst in-process run over 5 noise seeds x those latencies. One-sided:
  // tracking better than the in-process spread is never wrong (the stack's
  // figures come from 50 Hz telemetry, which can step over a peak).
  double pos_lo = 1e9, pos_hi = 0, ang_lo = 1e9, ang_hi = 0;
  for (uint32_t seed = 1; seed <= 5; ++seed)
    for (double d : {0.0, 0.01, 0.02, 0.03}) {
      const auto m = inProcess(control::WheelControl::kFuzzyPid, d, seed);
      pos_lo = std::min(pos_lo, m.max_pos_err_m);
      pos_hi = std::max(pos_hi, m.max_pos_err_m);
      ang_lo = std::min(ang_lo, m.max_ang_err_rad);
      ang_hi = std::max(ang_hi, m.max_ang_err_rad);
    }
  const double pos_limit = 1.2 * pos_hi, ang_limit = 1.2 * ang_hi;
  const auto [pos, ang] = trackCircle(s_emulator(), {"--rate", "2"}, "");
  std::printf("TRACK max position error: full stack %.4f m, in-process %.4f-%.4f m, limit %.4f m\n"
              "TRACK max angle error:    full stack %.4f rad, in-process %.4f-%.4f rad, limit %.4f rad\n",
              pos, pos_lo, pos_hi, pos_limit, ang, ang_lo, ang_hi, ang_limit);
  EXPECT_LE(pos, pos_limit) << "the full stack tracks the circle worse than the in-process experiment";
  EXPECT_LE(ang, ang_limit) << "the full stack tracks the circle worse than the in-process experiment";
}

// The same circle with the real firmware on the line (QEMU, mcu_sim --hil, in
// real time: 50 s), against the emulator's stack run in the same test: within
// 20 % of its maxima (issue 60's target; docs/firmware.md). Label `long`.
TEST(FirmwareStack, CircleTrackedWithin20PercentOfTheEmulator) {
  const auto [pos_e, ang_e] = trackCircle(s_emulator(), {"--rate", "2"}, "");
  const auto [pos_f, ang_f] = trackCircle(s_emulator(), {}, firmwareImage());
  std::printf("TRACK max position error: emulator %.4f m, firmware %.4f m (%+.0f %%)\n"
              "TRACK max angle error:    emulator %.4f rad, firmware %.4f rad (%+.0f %%)\n",
              pos_e, pos_f, 100 * (pos_f / pos_e - 1), ang_e, ang_f, 100 * (ang_f / ang_e - 1));
  EXPECT_LE(pos_f, 1.2 * pos_e);
  EXPECT_LE(ang_f, 1.2 * ang_e);
}
