#include "sim/mcu_sim/sim_options.hpp"


namespace inspect::sim {

std::string simUsage() {
  return "usage: mcu_sim --world FILE [options]\n"
         "Emulates the robot's MCU on a pseudo-terminal and simulates the world around it.\n"
         "\n"
         "  --world FILE     world file (config/worlds/*.yaml), required\n"
         "  --robot FILE     robot config (default: config/robot.yaml, relative to the working directory)\n"
         "  --pty-link PATH  also make PATH a symlink to the serial device (removed on exit)\n"
         "  --truth FILE     write the ground-truth CSV log (docs/simulator.md)\n"
         "  --frame-log FILE also log every sensor frame sent (id, sequence number, CRC; needs --truth),\n"
         "                   to check what a receiver accepted against what was sent (docs/failsafes.md)\n"
         "  --rate F         run F times faster than real time, F in [0.1, 100] (default 1)\n"
         "  --duration S     stop after S seconds of simulated time, S in (0, 1e6] (default: until SIGINT/SIGTERM)\n"
         "  --seed N         seed of the sensor noise, integer >= 0 (default 1)\n"
         "  --people-wait-motion  pedestrians stand at their start points and their clock (start_s,\n"
         "                   pauses) starts when the robot is first commanded to move, so a scenario\n"
         "                   plays the same however long the robot takes to connect\n"
         "  --help           print this help and exit\n";
}

SimOptions parseSimOptions(const std::vector<std::string>& args) {
  SimOptions o;
  bool have_world = false;
  cli::ArgReader a(args);
  while (a.next()) {
    if (a.isHelp()) o.help = true;
    else if (a.is("--world")) o.world_path = a.text(), have_world = true;
    else if (a.is("--robot")) o.robot_path = a.path();
    else if (a.is("--pty-link")) o.pty_link = a.path();
    else if (a.is("--truth")) o.truth_path = a.path();
    else if (a.is("--frame-log")) o.frame_log_path = a.path();
    else if (a.is("--people-wait-motion")) o.people_wait_motion = true;
    else if (a.is("--rate")) o.rate = a.number(0.1, 100.0);
    else if (a.is("--duration")) o.duration_s = a.numberAbove(0.0, 1e6);
    else if (a.is("--seed")) o.seed = a.unsignedInteger();
    else a.unknown();
  }
  if (!o.help && (!have_world || o.world_path.empty())) throw cli::UsageError("--world: required");
  if (!o.help && !o.frame_log_path.empty() && o.truth_path.empty()) throw cli::UsageError("--frame-log: needs --truth");
  return o;
}

}  // namespace inspect::sim
