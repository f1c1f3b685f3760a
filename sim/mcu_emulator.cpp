#include "sim/mcu_emulator.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>

namespace inspect::sim {
namespace {

int16_t toI16(double v) { return static_cast<int16_t>(std::clamp<long>(std::lround(v), INT16_MIN, INT16_MAX)); }

// Cumulative travel in 0.1 mm, wrapping like the firmware's int32 counter.
int32_t wrapDisp(double travel_m) {
  const auto ticks = static_cast<int64_t>(std::llround(travel_m * 10000.0));
  return static_cast<int32_t>(static_cast<uint32_t>(static_cast<uint64_t>(ticks)));
}

double simSeconds(uint64_t ms) { return static_cast<double>(ms) / 1000.0; }

}  // namespace

McuEmulator::McuEmulator(const config::RobotConfig& robot, uint64_t seed, SimObserver* observer)
    : max_wheel_rad_s_(robot.limits.max_wheel_speed_rad_s),
      gas_channels_(std::min<std::size_t>(robot.gas.channels.size(), serial::kGasChannels)),
      speed_noise_rad_s_(robot.motor.speed_noise_m_s / robot.geometry.wheel_radius_m),
      heading_noise_rad_(robot.motor.heading_noise_rad),
      observer_(observer),
      rng_(seed) {}

void McuEmulator::event(uint64_t now_ms, std::string_view name, std::string_view detail) {
  if (observer_) observer_->onEvent(simSeconds(now_ms), name, detail);
}

void McuEmulator::receive(std::span<const uint8_t> bytes, uint64_t now_ms) {
  decoder_.feed(bytes, [&](const serial::Message& m, uint8_t seq) { apply(m, seq, now_ms); });
}

void McuEmulator::apply(const serial::Message& msg, uint8_t seq, uint64_t now_ms) {
  std::visit(
      [&](const auto& m) {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, serial::WheelCommand>) {
          applyWheel(m, seq, now_ms);
        } else if constexpr (std::is_same_v<T, serial::Heartbeat>) {
          last_heartbeat_ms_ = now_ms;
          host_silent_ = false;
        } else if constexpr (std::is_same_v<T, serial::PtzCommand>) {
          ptz_ = m;
          if (m.flags & 0x01) ptz_.pan_0p1mrad = ptz_.tilt_0p1mrad = 0;
          event(now_ms, "ptz", ptzEventDetail(ptz_.pan_0p1mrad, ptz_.tilt_0p1mrad, m.flags));
        }
        // A SensorFrame from the host is meaningless to the MCU: ignored.
      },
      msg);
}

void McuEmulator::applyWheel(const serial::WheelCommand& c, uint8_t seq, uint64_t now_ms) {
  if (observer_) observer_->onCommand(simSeconds(now_ms), seq, c);
  ++commands_applied_;
  last_cmd_ms_ = now_ms;
  cmd_seq_echo_ = seq;
  if (watchdog_tripped_) {
    watchdog_tripped_ = false;
    event(now_ms, "watchdog_clear", "seq=" + std::to_string(seq));
  }
  if (c.flags & serial::WheelCommand::kEnable) {
    auto clamp = [&](int16_t mrad_s) { return std::clamp(mrad_s / 1000.0, -max_wheel_rad_s_, max_wheel_rad_s_); };
    setpoint_ = {clamp(c.left_mrad_s), clamp(c.right_mrad_s)};
  } else {
    setpoint_ = {};
  }
}

void McuEmulator::tick(uint64_t now_ms) {
  if (!watchdog_tripped_ && now_ms - last_cmd_ms_ >= kWatchdog_ms) {
    watchdog_tripped_ = true;
    setpoint_ = {};
    event(now_ms, "watchdog_trip", std::to_string(now_ms - last_cmd_ms_));
  }
  if (!host_silent_ && now_ms - last_heartbeat_ms_ >= kHostSilent_ms) {
    host_silent_ = true;
    event(now_ms, "host_silent", std::to_string(now_ms - last_heartbeat_ms_));
  }
  battery_mv_ = batteryMvAt(now_ms);
}

uint16_t McuEmulator::batteryMvAt(uint64_t now_ms) {
  const double drained = kBatteryStart_mv - kBatteryDrain_mv_per_s * simSeconds(now_ms);
  return static_cast<uint16_t>(std::max(0.0, std::round(drained)));
}

uint16_t McuEmulator::faults() const {
  uint16_t f = 0;
  if (watchdog_tripped_) f |= serial::kFaultWatchdog;
  if (host_silent_) f |= serial::kFaultHostSilent;
  if (battery_mv_ < kBatteryLow_mv) f |= serial::kFaultBatteryLow;
  if (gas_fault_) f |= serial::kFaultGasSensor;
  return f;
}

serial::SensorFrame McuEmulator::sendSensorFrame(uint64_t now_ms, const McuInputs& in, std::vector<uint8_t>& tx) {
  std::uniform_real_distribution<double> speed_noise(-speed_noise_rad_s_, speed_noise_rad_s_);
  std::uniform_real_distribution<double> heading_noise(-heading_noise_rad_, heading_noise_rad_);
  serial::SensorFrame f;
  f.mcu_time_ms = static_cast<uint32_t>(now_ms);
  f.wheel_speed_mrad_s = {toI16((in.truth.wheel.left_rad_s + speed_noise(rng_)) * 1000.0),
                          toI16((in.truth.wheel.right_rad_s + speed_noise(rng_)) * 1000.0)};
  f.wheel_disp_0p1mm = {wrapDisp(in.truth.wheel_travel_left_m), wrapDisp(in.truth.wheel_travel_right_m)};
  const double heading = control::wrapAngle(in.truth.pose.theta_rad + heading_noise(rng_));
  f.heading_0p1mrad = static_cast<int16_t>(std::clamp<long>(std::lround(heading * 10000.0), -31416, 31416));
  f.ultrasonic_mm = in.ultrasonic_mm;
  f.grayscale = in.grayscale;
  f.gas_raw = in.gas_raw;
  gas_fault_ = false;
  for (std::size_t i = 0; i < gas_channels_; ++i) gas_fault_ = gas_fault_ || in.gas_raw[i] == config::kGasNoData;
  f.battery_mv = battery_mv_;
  f.faults = faults();
  f.cmd_seq_echo = cmd_seq_echo_;
  const auto enc = encoder_.encode(f);
  tx.insert(tx.end(), enc.bytes.begin(), enc.bytes.begin() + static_cast<std::ptrdiff_t>(enc.size));
  ++frames_sent_;
  if (observer_) observer_->onFrameSent(simSeconds(now_ms), enc.span(), f.mcu_time_ms);
  return f;
}

}  // namespace inspect::sim
