#include "firmware/core/analog_inputs.hpp"

#include "shared/serial/messages.hpp"

#include <algorithm>
#include <cmath>

namespace inspect::firmware {

namespace {
constexpr float kLoopMinA = 4e-3f, kLoopSpanA = 16e-3f;
constexpr float kFaultBelowA = 3.6e-3f, kFaultAboveA = 21e-3f;  // NAMUR NE 43
}  // namespace

uint16_t gasCount(const McuSettings& s, const GasChannelSettings& ch, uint16_t adc_counts) {
  const float amps = static_cast<float>(adc_counts) / kAdcFullScale * kAdcVref / s.gas_shunt_ohm;
  if (amps < kFaultBelowA || amps > kFaultAboveA) return serial::kGasNoData;
  const float value = ch.range_min + (amps - kLoopMinA) / kLoopSpanA * (ch.range_max - ch.range_min);
  const float count = std::round(value / ch.scale);
  return static_cast<uint16_t>(std::clamp(count, 0.0f, 65534.0f));  // 0xFFFF is the fault
}

uint16_t gasAdcCounts(const McuSettings& s, const GasChannelSettings& ch, float value) {
  const float amps = kLoopMinA + (value - ch.range_min) / (ch.range_max - ch.range_min) * kLoopSpanA;
  const float counts = std::round(amps * s.gas_shunt_ohm / kAdcVref * kAdcFullScale);
  return static_cast<uint16_t>(std::clamp(counts, 0.0f, kAdcFullScale));
}

uint16_t batteryMv(const McuSettings& s, uint16_t adc_counts) {
  const float mv = static_cast<float>(adc_counts) / kAdcFullScale * kAdcVref * 1000.0f * s.battery_divider;
  return static_cast<uint16_t>(std::clamp(std::round(mv), 0.0f, 65535.0f));
}

uint16_t batteryAdcCounts(const McuSettings& s, uint16_t mv) {
  const float counts = std::round(static_cast<float>(mv) / 1000.0f / s.battery_divider / kAdcVref * kAdcFullScale);
  return static_cast<uint16_t>(std::clamp(counts, 0.0f, kAdcFullScale));
}

void BatteryMonitor::update(uint16_t mv) {
  if (!low_ && mv < s_.battery_low_mv) low_ = true;
  else if (low_ && mv > s_.battery_clear_mv) low_ = false;
}

bool Debounced::update(bool raw) {
  if (raw == state_) {
    same_ = 0;
  } else if (++same_ >= debounce_ms_) {
    state_ = raw;
    same_ = 0;
  }
  return state_;
}

}  // namespace inspect::firmware
