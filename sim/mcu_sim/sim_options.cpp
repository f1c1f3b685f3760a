#include "sim/mcu_sim/sim_options.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace inspect::sim {
namespace {

double parseNumber(const std::string& flag, const std::string& v, double min, double max, const char* range) {
  char* end = nullptr;
  const double d = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0' || !std::isfinite(d)) throw UsageError(flag + ": '" + v + "' is not a number");
  if (d < min || d > max) throw UsageError(flag + ": " + v + " is out of range " + range);
  return d;
}

}  // namespace

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
  for (std::size_t i = 0; i < args.size(); ++i) {
    std::string flag = args[i];
    std::optional<std::string> inline_value;
    if (const auto eq = flag.find('='); flag.rfind("--", 0) == 0 && eq != std::string::npos) {
      inline_value = flag.substr(eq + 1);
      flag = flag.substr(0, eq);
    }
    if (flag == "--help" || flag == "-h") {
      o.help = true;
      continue;
    }
    auto value = [&]() -> std::string {
      if (inline_value) return *inline_value;
      if (i + 1 >= args.size()) throw UsageError(flag + ": missing value");
      return args[++i];
    };
    if (flag == "--world") {
      o.world_path = value();
      have_world = true;
    } else if (flag == "--robot") {
      o.robot_path = value();
    } else if (flag == "--pty-link") {
      o.pty_link = value();
      if (o.pty_link.empty()) throw UsageError("--pty-link: empty path");
    } else if (flag == "--truth") {
      o.truth_path = value();
      if (o.truth_path.empty()) throw UsageError("--truth: empty path");
    } else if (flag == "--frame-log") {
      o.frame_log_path = value();
      if (o.frame_log_path.empty()) throw UsageError("--frame-log: empty path");
    } else if (flag == "--people-wait-motion") {
      o.people_wait_motion = true;
    } else if (flag == "--rate") {
      o.rate = parseNumber(flag, value(), 0.1, 100.0, "[0.1, 100]");
    } else if (flag == "--duration") {
      const std::string v = value();
      o.duration_s = parseNumber(flag, v, 0.0, 1e6, "(0, 1e6]");
      if (*o.duration_s <= 0.0) throw UsageError("--duration: " + v + " is out of range (0, 1e6]");
    } else if (flag == "--seed") {
      const std::string v = value();
      char* end = nullptr;
      errno = 0;
      const unsigned long long s = std::strtoull(v.c_str(), &end, 10);
      if (v.empty() || *end != '\0' || v[0] == '-' || errno != 0)
        throw UsageError("--seed: '" + v + "' is not a non-negative integer");
      o.seed = s;
    } else {
      throw UsageError(flag + ": unknown option (see --help)");
    }
  }
  if (!o.help && (!have_world || o.world_path.empty())) throw UsageError("--world: required");
  if (!o.help && !o.frame_log_path.empty() && o.truth_path.empty()) throw UsageError("--frame-log: needs --truth");
  return o;
}

}  // namespace inspect::sim
