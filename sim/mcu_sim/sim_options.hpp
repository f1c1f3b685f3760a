#pragma once
// Command line of mcu_sim.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "shared/util/cli_args.hpp"

namespace inspect::sim {

/// One camera head's pictures (--camera, --wide-camera).
struct CameraOutput {
  std::string path;  // empty: not rendered; else the frame slot its view is written to
  int width = 640;   // --camera-size / --wide-camera-size WxH, each in [64, 4096]
  int height = 480;
  double fps = 30.0; // [1, 120]
};

/// Parsed mcu_sim arguments.
struct SimOptions {
  std::string world_path;
  std::string robot_path = "config/robot.yaml";
  std::string pty_link;              // empty: no symlink
  std::string hil_device;            // --hil: the firmware board's HIL link (a tty); empty: the MCU is emulated
  std::string truth_path;            // empty: no truth log
  std::string frame_log_path;        // empty: no log of the sensor frames sent (needs truth_path)
  double rate = 1.0;                 // sim seconds per wall second, [0.1, 100]
  std::optional<double> duration_s;  // sim seconds; empty: until SIGINT/SIGTERM
  uint64_t seed = 1;
  int realtime_priority = 0;         // SCHED_FIFO priority of the simulation loop once started; 0: normal
  bool freeze_on_stall = false;      // a stall of this process pauses the world instead of a catch-up
  bool people_wait_motion = false;   // pedestrians' clock starts at the robot's first wheel motion
  CameraOutput camera;               // the PTZ head
  CameraOutput wide_camera{"", 640, 480, 15.0};  // the robot config's wide_camera head
  bool help = false;
};

/// Parses argv (without argv[0]); throws cli::UsageError naming the flag.
SimOptions parseSimOptions(const std::vector<std::string>& args);
/// The --help text.
std::string simUsage();

}  // namespace inspect::sim
