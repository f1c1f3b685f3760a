#pragma once
// The firmware's one core, made of the settings config/robot.yaml gave the
// build (mcu_settings_gen.hpp): what a board's main() runs.
#include "firmware/core/firmware_core.hpp"

namespace inspect::firmware {

/// The core, constructed on first use (no heap: a static object).
FirmwareCore& firmwareCore();

}  // namespace inspect::firmware
