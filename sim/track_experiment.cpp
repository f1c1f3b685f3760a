// Quick exploration driver (replaced by the full experiment program).
#include <cstdio>
#include <cstdlib>
#include <string>

#include "shared/config/control_config.hpp"
#include "sim/closed_loop.hpp"

using namespace inspect;

int main(int argc, char** argv) {
  auto robot = config::loadRobotConfigFile("config/robot.yaml");
  auto ctl = config::loadControlConfigFile("config/control.yaml");
  if (argc > 1) robot.motor.time_constant_s = std::atof(argv[1]);
  if (argc > 2) ctl.tracker.pid.derivative_filter_s = std::atof(argv[2]);
  if (argc > 3) ctl.tracker.feedforward = std::atoi(argv[3]) != 0;
  config::applyRobot(ctl, robot);
  auto sched = config::loadScheduler(ctl);
  for (auto wc : {control::WheelControl::kDirect, control::WheelControl::kPid, control::WheelControl::kFuzzyPid}) {
    sim::ClosedLoopConfig cfg;
    cfg.robot = robot;
    cfg.tracker = ctl.tracker;
    cfg.tracker.wheel_control = wc;
    auto res = sim::runClosedLoop(cfg, control::makeCircle({0, 0, 0}, 3.5, 0.5), sched, false);
    const auto& m = res.metrics;
    std::printf("%-10s maxpos %.4f maxang %.4f rmspos %.4f conv %.2f %.2f effort %.1f var %.1f sat %.2f final %.4f\n",
                control::toString(wc), m.max_pos_err_m, m.max_ang_err_rad, m.rms_pos_err_m, m.converge_pos_s,
                m.converge_ang_s, m.effort, m.command_variation, m.saturated_s, m.final_pos_err_m);
  }
}
