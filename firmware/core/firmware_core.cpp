#include "firmware/core/firmware_core.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <type_traits>

namespace inspect::firmware {

FirmwareCore::FirmwareCore(const McuSettings& s)
    : s_(s),
      left_(s, kPeriodS),
      right_(s, kPeriodS),
      odometry_(s),
      ultrasonic_(s),
      obstacle_(s),
      battery_(s),
      ptz_(s, kPeriodS) {}

void FirmwareCore::receive(std::span<const uint8_t> bytes, uint32_t now_ms) {
  decoder_.feed(bytes, [&](const serial::Message& m, uint8_t seq) { apply(m, seq, now_ms); });
  counters_.rx = decoder_.counters();
}

void FirmwareCore::apply(const serial::Message& msg, uint8_t seq, uint32_t now_ms) {
  if (const auto* c = std::get_if<serial::WheelCommand>(&msg)) {
    ++counters_.wheel_commands;
    last_cmd_ms_ = now_ms;
    watchdog_ = false;
    cmd_seq_echo_ = seq;
    enabled_ = (c->flags & serial::WheelCommand::kEnable) != 0;
    commanded_ = {c->left_mrad_s / 1000.0f, c->right_mrad_s / 1000.0f};  // clamped by the speed loops
  } else if (std::holds_alternative<serial::Heartbeat>(msg)) {
    last_heartbeat_ms_ = now_ms;
    host_silent_ = false;
  } else if (const auto* p = std::get_if<serial::PtzCommand>(&msg)) {
    ptz_.setTarget(p->pan_0p1mrad, p->tilt_0p1mrad, (p->flags & 0x01) != 0);
  } else {
    ++counters_.rx_ignored;  // a SensorFrame is the MCU's own
  }
}

PeripheralOutputs FirmwareCore::tick(uint32_t now_ms, const PeripheralInputs& in) {
  if (!booted_) {
    booted_ = true;
    last_cmd_ms_ = last_heartbeat_ms_ = now_ms;
    next_frame_ms_ = now_ms;  // the first frame at once
  }
  // Timers (uint32 differences: right across the 49.7-day wrap).
  if (!watchdog_ && now_ms - last_cmd_ms_ >= McuSettings::kWatchdogMs) {
    watchdog_ = true;
    ++counters_.watchdog_trips;
  }
  if (!host_silent_ && now_ms - last_heartbeat_ms_ >= McuSettings::kHostSilentMs) host_silent_ = true;
  const bool estop = estop_.update(in.estop_pressed);
  motor_fault_ = in.motor_driver_fault;

  PeripheralOutputs out;
  out.trigger = ultrasonic_.tick(now_ms, in.echo);
  const auto ranges = ultrasonic_.rangesMm();
  obstacle_.update(ranges[serial::kFrontLeft], ranges[serial::kFrontRight]);

  const bool drive = enabled_ && !watchdog_ && !estop && !motor_fault_;
  applied_ = drive ? commanded_ : std::array<float, 2>{};
  obstacle_.limit(applied_[0], applied_[1]);
  out.duty = {left_.step(applied_[0], drive, in.encoder[0]), right_.step(applied_[1], drive, in.encoder[1])};
  out.brake = !drive;
  ptz_.step();
  out.servo_us = ptz_.pulsesUs();

  if (static_cast<int32_t>(now_ms - next_frame_ms_) >= 0) {
    next_frame_ms_ += McuSettings::kFramePeriodMs;
    if (static_cast<int32_t>(now_ms - next_frame_ms_) >= 0) next_frame_ms_ = now_ms + McuSettings::kFramePeriodMs;
    sendFrame(now_ms, in);
  }
  return out;
}

void FirmwareCore::sendFrame(uint32_t now_ms, const PeripheralInputs& in) {
  serial::SensorFrame& f = frame_;
  f.mcu_time_ms = now_ms;
  auto mrad = [](float rad_s) {
    return static_cast<int16_t>(std::clamp(std::lround(rad_s * 1000.0f), -32768L, 32767L));
  };
  f.wheel_speed_mrad_s = {mrad(left_.speedRadS()), mrad(right_.speedRadS())};
  odometry_.update(left_.encoder().total(), right_.encoder().total());
  f.wheel_disp_0p1mm = odometry_.displacement0p1mm();
  f.heading_0p1mrad = odometry_.heading0p1mrad();
  f.ultrasonic_mm = ultrasonic_.rangesMm();
  f.grayscale = in.grayscale;
  gas_fault_ = false;
  for (std::size_t i = 0; i < f.gas_raw.size(); ++i) {
    f.gas_raw[i] = i < s_.gas_channel_count ? gasCount(s_, s_.gas[i], in.gas_adc[i]) : 0;
    gas_fault_ = gas_fault_ || (i < s_.gas_channel_count && f.gas_raw[i] == serial::kGasNoData);
  }
  f.battery_mv = batteryMv(s_, in.battery_adc);
  battery_.update(f.battery_mv);
  f.faults = faults();
  f.cmd_seq_echo = cmd_seq_echo_;
  const serial::EncodedFrame enc = encoder_.encode(f);
  if (tx_len_ + enc.size > tx_.size()) {
    ++counters_.tx_overruns;  // the UART is behind: this frame is dropped whole, never cut
    return;
  }
  std::memcpy(tx_.data() + tx_len_, enc.bytes.data(), enc.size);
  tx_len_ += enc.size;
  ++counters_.frames_sent;
}

std::size_t FirmwareCore::takeTx(std::span<uint8_t> out) {
  const std::size_t n = std::min(out.size(), tx_len_);
  std::memcpy(out.data(), tx_.data(), n);
  std::memmove(tx_.data(), tx_.data() + n, tx_len_ - n);
  tx_len_ -= n;
  return n;
}

uint16_t FirmwareCore::faults() const {
  uint16_t f = 0;
  if (watchdog_) f |= serial::kFaultWatchdog;
  if (ultrasonic_.fault()) f |= serial::kFaultUltrasonic;
  if (gas_fault_) f |= serial::kFaultGasSensor;
  if (battery_.low()) f |= serial::kFaultBatteryLow;
  if (motor_fault_) f |= serial::kFaultMotorDriver;
  if (estop_.state()) f |= serial::kFaultEStopButton;
  if (host_silent_) f |= serial::kFaultHostSilent;
  if (obstacle_.active()) f |= serial::kFaultObstacleStop;
  return f;
}

}  // namespace inspect::firmware
