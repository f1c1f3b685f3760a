#pragma once
// The firmware's settings from a robot config (config/robot.yaml), on the host:
// for host tests and the simulators, and for the generator that writes them
// into the MCU build (firmware/tools/mcu_settings_gen.cpp).
#include <string>

#include "firmware/core/mcu_settings.hpp"
#include "shared/config/robot_config.hpp"

namespace inspect::firmware {

McuSettings settingsFrom(const config::RobotConfig& robot);

/// The settings as a C++ header (`inline constexpr McuSettings kMcuSettings`),
/// naming the file it came from.
std::string settingsHeader(const McuSettings& s, const std::string& source);

}  // namespace inspect::firmware
