#pragma once
// The ADC's readings as the sensor frame carries them.
// Gas: each channel a 4-20 mA transmitter across the shunt (gas_shunt_ohm):
// 4 mA = the channel's range_min, 20 mA = its range_max, the frame's count =
// value / scale (docs/serial-protocol.md gas_raw); under 3.6 mA or over 21 mA
// is a sensor fault (NAMUR NE 43): serial::kGasNoData (0xFFFF) and GAS_SENSOR.
// Battery: the pin's voltage times battery_divider, mV; BATTERY_LOW below
// battery_low_mv until above battery_clear_mv.
#include <array>
#include <cstdint>

#include "firmware/core/mcu_settings.hpp"

namespace inspect::firmware {

/// A gas channel's frame count from its ADC counts (0xFFFF: sensor fault).
uint16_t gasCount(const McuSettings& s, const GasChannelSettings& ch, uint16_t adc_counts);
/// The ADC counts a channel's transmitter gives for `value` (the inverse, for
/// simulators and tests; clamped to the ADC's range).
uint16_t gasAdcCounts(const McuSettings& s, const GasChannelSettings& ch, float value);

/// The battery's voltage, mV, from the ADC counts.
uint16_t batteryMv(const McuSettings& s, uint16_t adc_counts);
/// The ADC counts of a battery voltage (the inverse).
uint16_t batteryAdcCounts(const McuSettings& s, uint16_t mv);

class BatteryMonitor {
 public:
  explicit BatteryMonitor(const McuSettings& s) : s_(s) {}
  void update(uint16_t mv);
  bool low() const { return low_; }

 private:
  const McuSettings& s_;
  bool low_ = false;
};

/// A switch read every ms, taken as changed once it has read the same for
/// `debounce_ms` in a row (contact bounce lasts a few ms).
class Debounced {
 public:
  explicit Debounced(uint32_t debounce_ms) : debounce_ms_(debounce_ms) {}
  bool update(bool raw);
  bool state() const { return state_; }

 private:
  uint32_t debounce_ms_;
  bool state_ = false;
  uint32_t same_ = 0;
};

}  // namespace inspect::firmware
