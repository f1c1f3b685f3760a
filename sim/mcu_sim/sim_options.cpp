#include "sim/mcu_sim/sim_options.hpp"

#include <cstdio>
#include <tuple>

namespace inspect::sim {

std::string simUsage() {
  return "usage: mcu_sim --world FILE [options]\n"
         "Emulates the robot's MCU on a pseudo-terminal and simulates the world around it.\n"
         "\n"
         "  --world FILE     world file (config/worlds/*.yaml), required\n"
         "  --robot FILE     robot config (default: config/robot.yaml, relative to the working directory)\n"
         "  --pty-link PATH  also make PATH a symlink to the serial device (removed on exit)\n"
         "  --hil TTY        hardware-in-the-loop: the MCU is the real firmware (scripts/mcu_qemu.sh\n"
         "                   --hil-link TTY), not emulated: the world is sent to its board over TTY (encoder\n"
         "                   counts, echoes, ADC counts, line bits) and its PWM duty drives the motors;\n"
         "                   robot_client opens the board's own serial line. Real time only (no --rate,\n"
         "                   --pty-link or --frame-log; docs/firmware.md)\n"
         "  --truth FILE     write the ground-truth CSV log (docs/simulator.md)\n"
         "  --frame-log FILE also log every sensor frame sent (id, sequence number, CRC; needs --truth),\n"
         "                   to check what a receiver accepted against what was sent (docs/failsafes.md)\n"
         "  --rate F         run F times faster than real time, F in [0.1, 100] (default 1)\n"
         "  --duration S     stop after S seconds of simulated time, S in (0, 1e6] (default: until SIGINT/SIGTERM)\n"
         "  --seed N         seed of the sensor noise, integer >= 0 (default 1)\n"
         "  --people-wait-motion  pedestrians stand at their start points and their clock (start_s,\n"
         "                   pauses) starts when the robot is first commanded to move, so a scenario\n"
         "                   plays the same however long the robot takes to connect\n"
         "  --camera PATH    render what the robot's PTZ camera sees (walls, obstacles, floor lines,\n"
         "                   people) into the frame slot PATH (a file; /dev/shm/NAME keeps it in memory),\n"
         "                   for robot_client --video-source sim:PATH (docs/video.md)\n"
         "  --camera-size WxH  its picture size, each in [64, 4096] (default 640x480; needs --camera)\n"
         "  --camera-fps N   its frame rate on the wall clock, N in [1, 120] (default 30; needs --camera)\n"
         "  --wide-camera PATH  render what the robot's second, wide and fixed head sees (the robot\n"
         "                   config's wide_camera; docs/human-awareness.md) into the frame slot PATH, a\n"
         "                   sim:PATH video source\n"
         "  --wide-camera-size WxH, --wide-camera-fps N  its picture size and rate (default 640x480,\n"
         "                   15 fps; need --wide-camera)\n"
         "  --realtime-priority N  run the simulation loop SCHED_FIFO at priority N in [1, 99] once\n"
         "                   started (it stands for the MCU, a chip of its own: above robot_client's\n"
         "                   loop, e.g. 20; needs root or CAP_SYS_NICE, else a warning); 0 = normal (default)\n"
         "  --freeze-on-stall  when this process was not run for more than 30 ms (a loaded host), the\n"
         "                   simulated world waits for it instead of catching up in one step with the\n"
         "                   robot blind: the host's stall is not the robot's (stack tests that measure\n"
         "                   control quality; never for failsafe timing, which the stall is part of)\n"
         "  --help           print this help and exit\n";
}

SimOptions parseSimOptions(const std::vector<std::string>& args) {
  SimOptions o;
  bool have_world = false;
  bool camera_size = false, camera_fps = false, wide_size = false, wide_fps = false;
  cli::ArgReader a(args);
  while (a.next()) {
    if (a.isHelp()) o.help = true;
    else if (a.is("--world")) o.world_path = a.text(), have_world = true;
    else if (a.is("--robot")) o.robot_path = a.path();
    else if (a.is("--pty-link")) o.pty_link = a.path();
    else if (a.is("--hil")) o.hil_device = a.path();
    else if (a.is("--truth")) o.truth_path = a.path();
    else if (a.is("--frame-log")) o.frame_log_path = a.path();
    else if (a.is("--people-wait-motion")) o.people_wait_motion = true;
    else if (a.is("--rate")) o.rate = a.number(0.1, 100.0);
    else if (a.is("--duration")) o.duration_s = a.numberAbove(0.0, 1e6);
    else if (a.is("--seed")) o.seed = a.unsignedInteger();
    else if (a.is("--realtime-priority")) o.realtime_priority = static_cast<int>(a.integer(0, 99));
    else if (a.is("--freeze-on-stall")) o.freeze_on_stall = true;
    else if (a.is("--camera")) o.camera.path = a.path();
    else if (a.is("--camera-size")) std::tie(o.camera.width, o.camera.height) = a.pictureSize(), camera_size = true;
    else if (a.is("--camera-fps")) o.camera.fps = a.number(1.0, 120.0), camera_fps = true;
    else if (a.is("--wide-camera")) o.wide_camera.path = a.path();
    else if (a.is("--wide-camera-size")) std::tie(o.wide_camera.width, o.wide_camera.height) = a.pictureSize(), wide_size = true;
    else if (a.is("--wide-camera-fps")) o.wide_camera.fps = a.number(1.0, 120.0), wide_fps = true;
    else a.unknown();
  }
  if (!o.help && o.camera.path.empty() && camera_size) throw cli::UsageError("--camera-size: needs --camera");
  if (!o.help && o.camera.path.empty() && camera_fps) throw cli::UsageError("--camera-fps: needs --camera");
  if (!o.help && o.wide_camera.path.empty() && wide_size) throw cli::UsageError("--wide-camera-size: needs --wide-camera");
  if (!o.help && o.wide_camera.path.empty() && wide_fps) throw cli::UsageError("--wide-camera-fps: needs --wide-camera");
  if (!o.help && !o.camera.path.empty() && o.camera.path == o.wide_camera.path)
    throw cli::UsageError("--wide-camera: must not be --camera's slot");
  if (!o.help && (!have_world || o.world_path.empty())) throw cli::UsageError("--world: required");
  if (!o.help && !o.frame_log_path.empty() && o.truth_path.empty()) throw cli::UsageError("--frame-log: needs --truth");
  if (!o.help && !o.hil_device.empty()) {
    // The firmware runs on the wall clock and owns the Pi's line and its frames.
    if (o.rate != 1.0) throw cli::UsageError("--rate: the firmware in the loop runs in real time (--hil)");
    if (!o.pty_link.empty()) throw cli::UsageError("--pty-link: with --hil the Pi's line is the board's (scripts/mcu_qemu.sh --serial-link)");
    if (!o.frame_log_path.empty()) throw cli::UsageError("--frame-log: with --hil the firmware sends the frames");
    if (o.freeze_on_stall)
      throw cli::UsageError("--freeze-on-stall: with --hil the board's clock runs on through a stall, so the world must too");
  }
  return o;
}

}  // namespace inspect::sim
