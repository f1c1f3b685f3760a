// mcu_settings_gen: writes the firmware's settings header from a robot config.
//   mcu_settings_gen --robot config/robot.yaml --out build-firmware/mcu_settings_gen.hpp
// A wrong config value is named (file, key, allowed range) and nothing is written.
#include <cstdio>
#include <fstream>
#include <string>

#include "firmware/host/settings_from_config.hpp"
#include "shared/config/config_node.hpp"
#include "shared/util/cli_args.hpp"

int main(int argc, char** argv) {
  std::string robot = "config/robot.yaml", out;
  inspect::cli::readOrExit("mcu_settings_gen", argc, argv, [&](inspect::cli::ArgReader& a) {
    if (a.isHelp()) {
      std::puts("usage: mcu_settings_gen [--robot FILE] --out FILE\n"
                "Writes the MCU firmware's settings (config/robot.yaml's geometry, limits, ultrasonic,\n"
                "gas and mcu sections) as a C++ header (docs/firmware.md).");
      std::exit(0);
    } else if (a.is("--robot")) {
      robot = a.path();
    } else if (a.is("--out")) {
      out = a.path();
    } else {
      a.unknown();
    }
  });
  if (out.empty()) {
    std::fprintf(stderr, "mcu_settings_gen: --out FILE is required\n");
    return 2;
  }
  try {
    const auto settings = inspect::firmware::settingsFrom(inspect::config::loadRobotConfigFile(robot));
    const std::string text = inspect::firmware::settingsHeader(settings, robot);
    std::ofstream f(out);
    f << text;
    if (!f.flush()) {
      std::fprintf(stderr, "mcu_settings_gen: cannot write %s\n", out.c_str());
      return 1;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mcu_settings_gen: %s\n", e.what());
    return 1;
  }
  return 0;
}
