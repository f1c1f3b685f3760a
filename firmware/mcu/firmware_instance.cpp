#include "firmware/mcu/firmware_instance.hpp"

#include "mcu_settings_gen.hpp"

namespace inspect::firmware {

FirmwareCore& firmwareCore() {
  static FirmwareCore core(kMcuSettings);
  return core;
}

}  // namespace inspect::firmware
