#include "sim/hil_mcu.hpp"

#include <cmath>
#include <numbers>
#include <string>

#include "firmware/core/analog_inputs.hpp"
#include "firmware/core/ptz_servo.hpp"
#include "firmware/host/settings_from_config.hpp"
#include "sim/mcu_emulator.hpp"

namespace inspect::sim {

HilMcu::HilMcu(const config::RobotConfig& robot, SimObserver* observer)
    : settings_(firmware::settingsFrom(robot)), observer_(observer), wheel_radius_m_(robot.geometry.wheel_radius_m) {
  echo_.echo_flags = hil::HilSensors::kEchoRose;  // until a ping: nothing in range
}

void HilMcu::receive(std::span<const uint8_t> bytes, uint64_t now_ms) {
  decoder_.feed(bytes, [&](const hil::HilMessage& m, uint8_t) {
    const auto* out = std::get_if<hil::HilOutputs>(&m);
    if (!out) return;  // the board sends nothing else
    if (observer_ && out->ptz_target_0p1mrad != last_.ptz_target_0p1mrad) {
      // A new camera-mount target: the PtzCommand the firmware took, logged as the emulator logs it.
      observer_->onEvent(static_cast<double>(now_ms) / 1000.0, "ptz",
                         ptzEventDetail(out->ptz_target_0p1mrad[0], out->ptz_target_0p1mrad[1]));
    }
    if (!heard_) {
      readings_due_ = true;  // until now the board held the world still, gas at its transmitters' 4 mA
      answered_count_ = out->trigger_count;  // pings before the link came up are gone
      seq_ = static_cast<uint8_t>(out->input_seq + 1);
      first_seq_ = seq_;
    } else if (const auto past_first = static_cast<uint8_t>(out->input_seq - first_seq_);
               !inputs_taken_ && past_first >= 1 && past_first < 128) {
      inputs_taken_ = true;  // it took the frame after the first: the first readings (sent with or before it) too
    }
    last_ = *out;
    trackBoardClock(out->mcu_time_ms, now_ms);
    acked_seq_ = out->input_seq;
    heard_ = true;
    late_.record(static_cast<int64_t>(out->tick_late_us) * 1000);
    if (observer_ && out->tick_late_us >= kLateTickEvent_us) {
      // A tick this late: the firmware did not run (QEMU's vCPU was not), in the truth log as an event.
      observer_->onEvent(static_cast<double>(now_ms) / 1000.0, "late_tick",
                         "mcu_ms=" + std::to_string(out->mcu_time_ms) + " late_us=" + std::to_string(out->tick_late_us));
    }
  });
}

control::WheelSpeeds HilMcu::motorTargets() const {
  if (!heard_ || (last_.flags & hil::HilOutputs::kBrake)) return {0.0, 0.0};
  const double per_duty = 1.0 / (10000.0 * settings_.speed_ff);
  return {last_.duty_1e4[0] * per_duty, last_.duty_1e4[1] * per_duty};
}

std::array<double, 2> HilMcu::ptzRad() const {
  if (!heard_) return {0.0, 0.0};
  auto angle = [&](uint16_t us) { return (static_cast<double>(us) - firmware::PtzServo::kCentreUs) / settings_.servo_us_per_rad; };
  return {angle(last_.servo_us[0]), angle(last_.servo_us[1])};
}

void HilMcu::answerPing(uint16_t range_mm) {
  ++pings_;
  readings_due_ = true;
  answered_count_ = last_.trigger_count;
  echo_.echo_count = last_.trigger_count;
  if (range_mm == serial::kNoEcho) {
    echo_.echo_flags = hil::HilSensors::kEchoRose;  // still high when the slot ends
    echo_.echo_width_us = 0;
  } else {
    // Out and back at 343 m/s, as the firmware reads it (firmware/core/ultrasonic.cpp).
    echo_.echo_flags = hil::HilSensors::kEchoRose | hil::HilSensors::kEchoFell;
    echo_.echo_width_us = static_cast<uint32_t>(std::lround(range_mm * 2.0 / 0.343));
  }
}

void HilMcu::trackBoardClock(uint32_t mcu_time_ms, uint64_t now_ms) {
  // mcu_time_ms was the board's clock when it sent; it is at least that now.
  const int64_t offset = static_cast<int64_t>(mcu_time_ms) - static_cast<int64_t>(now_ms);
  if (!clock_known_ || offset > clock_offset_ms_) clock_offset_ms_ = offset;  // a less delayed report
  clock_known_ = true;
  if (now_ms >= window_start_ms_ + kClockWindow_ms) {
    // A whole window below the estimate by more than the slack: the board's
    // clock fell back (it restarts its schedule after a stall of 100 ms).
    if (window_any_ && window_best_ < clock_offset_ms_ - kClockSlack_ms) clock_offset_ms_ = window_best_;
    window_any_ = false;
    window_start_ms_ = now_ms;
  }
  if (!window_any_ || offset > window_best_) window_best_ = offset;
  window_any_ = true;
}

void HilMcu::sendEncoders(const PlantState& truth, uint64_t now_ms, std::vector<uint8_t>& tx) {
  const double counts_per_rad = settings_.encoder_counts_per_rev / (2.0 * std::numbers::pi);
  const double counts_per_m = counts_per_rad / wheel_radius_m_;
  auto counter = [&](double travel_m) {
    return static_cast<uint16_t>(static_cast<int64_t>(std::floor(travel_m * counts_per_m)) & 0xFFFF);
  };
  auto rate = [&](double rad_s) { return static_cast<int32_t>(std::lround(rad_s * counts_per_rad)); };
  hil::HilEncoders e;
  e.counter = {counter(truth.wheel_travel_left_m), counter(truth.wheel_travel_right_m)};
  e.rate_counts_s = {rate(truth.wheel.left_rad_s), rate(truth.wheel.right_rad_s)};
  e.board_ms = static_cast<uint16_t>(static_cast<int64_t>(now_ms) + clock_offset_ms_);
  if (!append(e, tx)) ++held_back_;  // no loss: the next carries newer counts
}

void HilMcu::sendSensors(uint64_t now_ms, uint8_t grayscale, const std::array<uint16_t, serial::kGasChannels>& gas_raw,
                         std::vector<uint8_t>& tx) {
  hil::HilSensors in = echo_;
  for (std::size_t i = 0; i < serial::kGasChannels; ++i) {
    const firmware::GasChannelSettings& ch = settings_.gas[i];
    if (i >= settings_.gas_channel_count || gas_raw[i] == serial::kGasNoData) {
      // No transmitter, or a failed one: the fault current.
      const float span = ch.range_max - ch.range_min;
      in.gas_adc[i] = firmware::gasAdcCounts(settings_, ch, ch.range_min - span * (4.0f - kFailedTransmitterMa) / 16.0f);
    } else {
      in.gas_adc[i] = firmware::gasAdcCounts(settings_, ch, static_cast<float>(gas_raw[i]) * ch.scale);
    }
  }
  in.battery_adc = firmware::batteryAdcCounts(settings_, McuEmulator::batteryMvAt(now_ms));
  in.grayscale = grayscale;
  in.switches = 0;
  if (append(in, tx)) {
    readings_due_ = readings_held_ = false;
    return;
  }
  if (!readings_held_) ++held_back_;
  readings_due_ = readings_held_ = true;
}

bool HilMcu::append(const hil::HilMessage& m, std::vector<uint8_t>& tx) {
  // Nothing before the board speaks (it holds the world still meanwhile), and
  // no more than kMaxInFlight frames it has not taken.
  if (!heard_ || static_cast<uint8_t>(seq_ - acked_seq_ - 1) >= kMaxInFlight) return false;
  const auto frame = hil::encodeHil(m, seq_++);
  tx.insert(tx.end(), frame.bytes.begin(), frame.bytes.begin() + static_cast<std::ptrdiff_t>(frame.size));
  ++frames_sent_;
  return true;
}

}  // namespace inspect::sim
