// mcu_sim: emulates the robot's MCU on a pseudo-terminal and simulates the
// world around it (docs/simulator.md).
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "shared/config/robot_config.hpp"
#include "shared/util/realtime.hpp"
#include "sim/mcu_sim/camera_feed.hpp"
#include "sim/mcu_sim/pty_port.hpp"
#include "sim/mcu_sim/realtime_runner.hpp"
#include "sim/mcu_sim/sim_options.hpp"
#include "sim/simulation.hpp"
#include "sim/mcu_sim/truth_log.hpp"
#include "sim/world_names.hpp"

using namespace inspect;

int main(int argc, char** argv) {
  sim::SimOptions opt;
  try {
    opt = sim::parseSimOptions(std::vector<std::string>(argv + 1, argv + argc));
  } catch (const cli::UsageError& e) {
    std::fprintf(stderr, "mcu_sim: %s\n", e.what());
    return 2;
  }
  if (opt.help) {
    std::fputs(sim::simUsage().c_str(), stdout);
    return 0;
  }
  try {
    sim::RealtimeRunner::installStopSignals();
    const config::RobotConfig robot = config::loadRobotConfigFile(opt.robot_path);
    sim::World world = sim::loadWorldFile(opt.world_path);
    const std::string world_name = world.name;
    std::unique_ptr<sim::TruthLog> truth;
    if (!opt.truth_path.empty()) truth = std::make_unique<sim::TruthLog>(opt.truth_path);
    if (truth && !opt.frame_log_path.empty()) truth->openFrameLog(opt.frame_log_path);
    sim::Simulation simulation(robot, std::move(world), opt.seed, truth.get());
    simulation.setPeopleWaitForMotion(opt.people_wait_motion);
    // The camera's slot exists before the serial device is announced, so a
    // client started on that announcement finds both.
    if (!opt.wide_camera.path.empty() && !robot.wide_camera)
      throw config::ConfigError(opt.robot_path + ": --wide-camera needs a wide_camera section (docs/human-awareness.md)");
    std::vector<std::unique_ptr<sim::CameraFeed>> cameras;  // the PTZ head, the wide head
    for (const bool wide : {false, true}) {
      const sim::CameraOutput& out = wide ? opt.wide_camera : opt.camera;
      if (out.path.empty()) continue;
      cameras.push_back(std::make_unique<sim::CameraFeed>(
          simulation.world(), wide ? *robot.wide_camera : robot.camera,
          sim::CameraFeedOptions{out.path, out.width, out.height, out.fps, !wide}));
      cameras.back()->publish(simulation);
      cameras.back()->start();
    }
    std::unique_ptr<sim::PtyPort> port_owner;
    if (opt.hil_device.empty()) {
      port_owner = std::make_unique<sim::PtyPort>(opt.pty_link);
      std::printf("mcu_sim: serial device %s\n", port_owner->slavePath().c_str());
      if (!opt.pty_link.empty()) std::printf("mcu_sim: linked at %s\n", opt.pty_link.c_str());
    } else {
      port_owner = std::make_unique<sim::PtyPort>(sim::PtyPort::Device{opt.hil_device});
      simulation.useHilFirmware(robot);
      std::printf("mcu_sim: hil link %s (the MCU is the firmware on its board)\n", opt.hil_device.c_str());
    }
    sim::PtyPort& port = *port_owner;
    if (!opt.camera.path.empty())
      std::printf("mcu_sim: camera %s (%dx%d at %g fps; robot_client --video-source sim:%s)\n",
                  opt.camera.path.c_str(), opt.camera.width, opt.camera.height, opt.camera.fps,
                  opt.camera.path.c_str());
    if (!opt.wide_camera.path.empty())
      std::printf("mcu_sim: wide camera %s (%dx%d at %g fps; a sim:%s video source)\n",
                  opt.wide_camera.path.c_str(), opt.wide_camera.width, opt.wide_camera.height, opt.wide_camera.fps,
                  opt.wide_camera.path.c_str());
    std::fflush(stdout);

    if (truth) {
      char detail[256];
      std::snprintf(detail, sizeof detail, "world=%s seed=%llu rate=%g device=%s", world_name.c_str(),
                    static_cast<unsigned long long>(opt.seed), opt.rate, port.slavePath().c_str());
      truth->onEvent(0.0, "start", detail);
    }
    sim::RealtimeRunner::Options run_opts{opt.rate, opt.duration_s, {}, opt.freeze_on_stall};
    bool board_announced = false;
    run_opts.on_caught_up = [&cameras, &board_announced](const sim::Simulation& s) {
      for (auto& c : cameras) c->publish(s);
      if (const sim::HilMcu* hil = s.hilMcu(); hil && !board_announced && hil->boardTookInputs()) {
        // The board has its first readings of the world: scripts/mcu_qemu.sh links the Pi's line now.
        std::printf("mcu_sim: hil board answered (its peripherals read the world)\n");
        std::fflush(stdout);
        board_announced = true;
      }
    };
    sim::RealtimeRunner runner(simulation, port, truth.get(), run_opts);
    // Real-time only now, start-up done: loading the world and the libraries
    // at SCHED_FIFO would hold a core from the other loops on the machine.
    if (const std::string why = util::enterRealtime(opt.realtime_priority); !why.empty())
      std::fprintf(stderr, "mcu_sim: warning: running at normal priority: %s\n", why.c_str());
    const sim::RunSummary r = runner.run();
    for (auto& c : cameras) c->stop();

    const std::string stats = sim::formatSerialStats(r.stats);
    std::printf("mcu_sim: final pose x=%.4f y=%.4f theta=%.4f\n", r.final_pose.x_m, r.final_pose.y_m,
                r.final_pose.theta_rad);
    std::printf("mcu_sim: %s\n", stats.c_str());
    for (const auto& c : cameras) std::printf("mcu_sim: %s\n", c->summary().c_str());
    if (const sim::HilMcu* hil = simulation.hilMcu()) {
      std::printf("mcu_sim: hil frames_in=%u errors=%u inputs_out=%llu held_back=%llu pings=%llu; %s\n",
                  hil->framesReceived(), hil->errors(), static_cast<unsigned long long>(hil->framesSent()),
                  static_cast<unsigned long long>(hil->framesHeldBack()),
                  static_cast<unsigned long long>(hil->pings()),
                  hil->tickLateness().summary("firmware control ticks late (TIM2)").c_str());
    }
    std::fflush(stdout);
    if (truth) {
      truth->comment(stats);
      std::printf("mcu_sim: %s\n", truth->writerSummary().c_str());
      std::fflush(stdout);
    }
    return 0;
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "mcu_sim: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mcu_sim: %s\n", e.what());
    return 1;
  }
}
