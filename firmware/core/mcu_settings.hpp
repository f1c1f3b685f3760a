#pragma once
// The firmware's settings: config/robot.yaml's, as constants. The MCU build
// gets them from the header scripts/build_firmware.sh generates
// (firmware/tools/mcu_settings_gen); host tests make them from a RobotConfig
// (firmware/host/settings_from_config.hpp). A plain aggregate: no heap, no
// construction at run time.
#include <array>
#include <cstdint>

#include "shared/serial/messages.hpp"

namespace inspect::firmware {

/// One gas channel of the sensor frame: a 4-20 mA transmitter read across the
/// shunt; 4 mA = range_min, 20 mA = range_max, the frame's value = reading / scale.
struct GasChannelSettings {
  float scale = 0.01f;  // unit per frame count
  float range_min = 0.0f;
  float range_max = 100.0f;
};

struct McuSettings {
  // Hub motors and encoders (robot.yaml geometry, limits, mcu).
  float wheel_radius_m = 0.2f;
  float track_m = 0.438f;
  float max_wheel_speed_rad_s = 5.0f;
  uint32_t encoder_counts_per_rev = 16384;
  float speed_kp = 0.2f;
  float speed_ki = 2.0f;
  float speed_ff = 0.154f;
  float response_tau_s = 0.2f;  // the set-point response the speed loop gives the Pi (robot.yaml motor.time_constant_s)
  // Ultrasonic sensors (robot.yaml ultrasonic, mcu).
  float ultrasonic_min_range_m = 0.02f;
  float ultrasonic_max_range_m = 4.5f;
  uint16_t ultrasonic_slot_ms = 30;
  uint8_t ultrasonic_missed_limit = 3;
  float obstacle_stop_m = 0.15f;  // 0 = off
  float obstacle_clear_m = 0.20f;
  // Gas channels (robot.yaml gas.channels, in slot order).
  uint8_t gas_channel_count = 0;
  std::array<GasChannelSettings, serial::kGasChannels> gas{};
  float gas_shunt_ohm = 150.0f;
  // Battery.
  float battery_divider = 11.0f;
  uint16_t battery_low_mv = 22200;
  uint16_t battery_clear_mv = 22600;
  // Camera mount servos.
  float ptz_slew_rad_s = 2.0944f;
  float servo_us_per_rad = 636.6f;
  // The protocol's timers (docs/serial-protocol.md): fixed, not configured.
  static constexpr uint32_t kWatchdogMs = 200;
  static constexpr uint32_t kHostSilentMs = 500;
  static constexpr uint32_t kFramePeriodMs = 10;     // 100 Hz sensor frames
  static constexpr uint32_t kEStopDebounceMs = 10;   // the button: this long pressed (or released) to count
};

/// The ADC: 12 bits over 3.3 V (STM32F4).
inline constexpr float kAdcVref = 3.3f;
inline constexpr float kAdcFullScale = 4095.0f;

}  // namespace inspect::firmware
