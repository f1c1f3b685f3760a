#pragma once
// Gas sensor channels (the `gas:` section of config/robot.yaml), read by
// robot_client (alarm logic, units) and mcu_sim (sensor simulation). Slot i of
// the serial sensor frame's gas_raw[] carries channel i: value = raw * scale;
// raw 0xFFFF means "no data" (the sensor dropped out; docs/serial-protocol.md).
#include <cstdint>
#include <string>
#include <vector>

#include "shared/config/config_node.hpp"
#include "shared/serial/messages.hpp"

namespace inspect::config {

/// Raw value a gas slot carries when its sensor gives no reading (the protocol's).
inline constexpr uint16_t kGasNoData = serial::kGasNoData;
/// Largest raw value that is a reading.
inline constexpr uint16_t kGasRawMax = 0xFFFE;

/// Which side of the thresholds is dangerous.
enum class AlarmDirection { Rising, Falling };

/// Another gas the sensor also responds to: reading += factor x that gas's concentration.
struct CrossSensitivity {
  std::string gas;      // channel name of the other gas, e.g. "H2S"
  double factor = 0.0;  // reading units per unit of the other gas
};

/// One gas channel: the sensor, its units and its alarm levels.
struct GasChannel {
  std::string name;              // short name, e.g. "CH4"; unique; what worlds' leaks name
  std::string gas;               // e.g. "methane"
  std::string unit;              // e.g. "%LEL", "ppm", "%vol"
  std::string sensor = "electrochemical";  // catalytic, electrochemical, ndir, pid, paramagnetic
  double scale = 0.01;           // unit per raw count (raw 0..0xFFFE)
  double range_min = 0.0;        // measuring range; a reading outside it is a sensor fault
  double range_max = 100.0;
  double t90_s = 10.0;           // first-order response: time to 90 % of a step
  double noise = 0.0;            // reading noise, standard deviation, unit (the simulator's)
  double background = 0.0;       // clean-air value (20.9 for O2)
  AlarmDirection direction = AlarmDirection::Rising;
  double alarm_low = 0.0;        // A1 (warning) threshold
  double alarm_high = 0.0;       // A2 (danger) threshold; beyond alarm_low in `direction`
  double hysteresis = 0.0;       // an alarm clears once the value is back past threshold -/+ this
  double min_duration_s = 1.0;   // beyond a threshold (or back) this long before raising (clearing)
  double stuck_s = 10.0;         // identical raw readings this long = "stuck" sensor fault
  std::vector<CrossSensitivity> cross;

  /// Time constant tau of the first-order response (T90 = tau ln 10).
  double tau_s() const;
  /// True when `value` is beyond `threshold` on the dangerous side.
  bool beyond(double value, double threshold) const {
    return direction == AlarmDirection::Rising ? value >= threshold : value <= threshold;
  }
};

/// Up to serial::kGasChannels channels, in frame-slot order.
struct GasConfig {
  std::vector<GasChannel> channels;
  double inlet_x_m = 0.25;  // where the sensors sample the air, robot frame (x ahead, y left)
  double inlet_y_m = 0.0;
  /// Index of the channel named `name`, or -1.
  int find(const std::string& name) const;
};

/// The default channels (as in config/robot.yaml): CH4 %LEL, H2S ppm, CO ppm, O2 %vol.
GasConfig defaultGasConfig();
/// Reads the `gas` section (a mapping with `channels`); absent = no gas channels. Throws ConfigError.
GasConfig loadGasConfig(const ConfigNode& gas_section, bool present);

}  // namespace inspect::config
