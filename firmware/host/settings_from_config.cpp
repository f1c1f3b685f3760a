#include "firmware/host/settings_from_config.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>

namespace inspect::firmware {

namespace {
constexpr double kPi = 3.14159265358979;

/// The shortest float literal of C++ that reads back as `v` (0.2f, not
/// 0.200000003f; 0 -> 0.0f, 1e-05 -> 1e-05f).
std::string num(float v) {
  char b[64];
  for (int digits = 6; digits <= 9; ++digits) {
    std::snprintf(b, sizeof b, "%.*g", digits, static_cast<double>(v));
    if (std::strtof(b, nullptr) == v) break;
  }
  std::string s = b;
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s + "f";
}
}  // namespace

McuSettings settingsFrom(const config::RobotConfig& r) {
  McuSettings s;
  s.wheel_radius_m = static_cast<float>(r.geometry.wheel_radius_m);
  s.track_m = static_cast<float>(r.geometry.track_m);
  s.max_wheel_speed_rad_s = static_cast<float>(r.limits.max_wheel_speed_rad_s);
  s.encoder_counts_per_rev = static_cast<uint32_t>(r.mcu.encoder_counts_per_rev);
  s.speed_kp = static_cast<float>(r.mcu.speed_kp);
  s.speed_ki = static_cast<float>(r.mcu.speed_ki);
  s.speed_ff = static_cast<float>(r.mcu.speed_ff);
  s.response_tau_s = static_cast<float>(r.motor.time_constant_s);
  s.ultrasonic_min_range_m = static_cast<float>(r.ultrasonic.min_range_m);
  s.ultrasonic_max_range_m = static_cast<float>(r.ultrasonic.max_range_m);
  s.ultrasonic_slot_ms = static_cast<uint16_t>(r.mcu.ultrasonic_slot_ms);
  s.ultrasonic_missed_limit = static_cast<uint8_t>(r.mcu.ultrasonic_missed_limit);
  s.obstacle_stop_m = static_cast<float>(r.mcu.obstacle_stop_m);
  s.obstacle_clear_m = static_cast<float>(r.mcu.obstacle_clear_m);
  s.gas_channel_count = static_cast<uint8_t>(std::min<std::size_t>(r.gas.channels.size(), s.gas.size()));
  for (std::size_t i = 0; i < s.gas_channel_count; ++i) {
    const auto& c = r.gas.channels[i];
    s.gas[i] = {static_cast<float>(c.scale), static_cast<float>(c.range_min), static_cast<float>(c.range_max)};
  }
  s.gas_shunt_ohm = static_cast<float>(r.mcu.gas_shunt_ohm);
  s.battery_divider = static_cast<float>(r.mcu.battery_divider);
  s.battery_low_mv = static_cast<uint16_t>(r.mcu.battery_low_mv);
  s.battery_clear_mv = static_cast<uint16_t>(r.mcu.battery_clear_mv);
  s.ptz_slew_rad_s = static_cast<float>(r.mcu.ptz_slew_deg_s * kPi / 180.0);
  s.servo_us_per_rad = static_cast<float>(r.mcu.servo_us_per_deg * 180.0 / kPi);
  return s;
}

std::string settingsHeader(const McuSettings& s, const std::string& source) {
  std::string h = "#pragma once\n// Generated from " + source +
                  " by firmware/tools/mcu_settings_gen (scripts/build_firmware.sh). Do not edit.\n"
                  "#include \"firmware/core/mcu_settings.hpp\"\n\nnamespace inspect::firmware {\n\n"
                  "inline constexpr McuSettings kMcuSettings = [] {\n  McuSettings s;\n";
  auto f = [&](const char* name, float v) { h += std::string("  s.") + name + " = " + num(v) + ";\n"; };
  auto u = [&](const char* name, unsigned long v) { h += std::string("  s.") + name + " = " + std::to_string(v) + ";\n"; };
  f("wheel_radius_m", s.wheel_radius_m);
  f("track_m", s.track_m);
  f("max_wheel_speed_rad_s", s.max_wheel_speed_rad_s);
  u("encoder_counts_per_rev", s.encoder_counts_per_rev);
  f("speed_kp", s.speed_kp);
  f("speed_ki", s.speed_ki);
  f("speed_ff", s.speed_ff);
  f("response_tau_s", s.response_tau_s);
  f("ultrasonic_min_range_m", s.ultrasonic_min_range_m);
  f("ultrasonic_max_range_m", s.ultrasonic_max_range_m);
  u("ultrasonic_slot_ms", s.ultrasonic_slot_ms);
  u("ultrasonic_missed_limit", s.ultrasonic_missed_limit);
  f("obstacle_stop_m", s.obstacle_stop_m);
  f("obstacle_clear_m", s.obstacle_clear_m);
  u("gas_channel_count", s.gas_channel_count);
  for (std::size_t i = 0; i < s.gas_channel_count; ++i)
    h += "  s.gas[" + std::to_string(i) + "] = {" + num(s.gas[i].scale) + ", " + num(s.gas[i].range_min) + ", " +
         num(s.gas[i].range_max) + "};\n";
  f("gas_shunt_ohm", s.gas_shunt_ohm);
  f("battery_divider", s.battery_divider);
  u("battery_low_mv", s.battery_low_mv);
  u("battery_clear_mv", s.battery_clear_mv);
  f("ptz_slew_rad_s", s.ptz_slew_rad_s);
  f("servo_us_per_rad", s.servo_us_per_rad);
  h += "  return s;\n}();\n\n}  // namespace inspect::firmware\n";
  return h;
}

}  // namespace inspect::firmware
