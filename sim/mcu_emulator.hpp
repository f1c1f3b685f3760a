#pragma once
// The STM32's protocol logic: decodes host messages, applies wheel set-points,
// runs the 200 ms command watchdog and 500 ms heartbeat monitor, and builds
// the 100 Hz sensor frames. Pure: no I/O, time is an argument (ms of sim time).
#include <array>
#include <cstdint>
#include <optional>
#include <random>
#include <span>
#include <vector>

#include "shared/config/robot_config.hpp"
#include "shared/control/diff_drive.hpp"
#include "shared/serial/frame_codec.hpp"
#include "shared/serial/messages.hpp"
#include "sim/robot_plant.hpp"
#include "sim/sim_observer.hpp"

namespace inspect::sim {

/// Raw sensor values the world simulation hands to the MCU for one frame.
struct McuInputs {
  PlantState truth;
  std::array<uint16_t, serial::kUltrasonicCount> ultrasonic_mm{};
  uint8_t grayscale = 0;
  std::array<uint16_t, serial::kGasChannels> gas_raw{};
};

/// Emulated MCU firmware.
class McuEmulator {
 public:
  static constexpr uint64_t kWatchdog_ms = 200;
  static constexpr uint64_t kHostSilent_ms = 500;
  static constexpr uint16_t kBatteryStart_mv = 25200;
  static constexpr double kBatteryDrain_mv_per_s = 0.5;
  static constexpr uint16_t kBatteryLow_mv = 22200;

  McuEmulator(const config::RobotConfig& robot, uint64_t seed, SimObserver* observer = nullptr);

  /// The simulated battery's voltage at now_ms (mV): what either MCU reads,
  /// this emulator or the firmware in the loop (sim/hil_mcu.hpp).
  static uint16_t batteryMvAt(uint64_t now_ms);

  /// Feeds bytes from the host received at now_ms. Corrupt frames are only counted.
  void receive(std::span<const uint8_t> bytes, uint64_t now_ms);
  /// Runs the MCU's timers at now_ms (call every simulation step).
  void tick(uint64_t now_ms);
  /// Builds the sensor frame for now_ms from the inputs and appends its encoded bytes to tx.
  serial::SensorFrame sendSensorFrame(uint64_t now_ms, const McuInputs& in, std::vector<uint8_t>& tx);

  /// Wheel set-points in force (zero when disabled or after the watchdog).
  control::WheelSpeeds setpoints() const { return setpoint_; }
  /// McuFault bits at the current state (GAS_SENSOR: the last frame had a configured channel with no data).
  uint16_t faults() const;
  bool watchdogTripped() const { return watchdog_tripped_; }
  /// Sim time (ms) at which the watchdog trips unless a wheel command comes first; empty when tripped.
  std::optional<uint64_t> watchdogDeadlineMs() const {
    if (watchdog_tripped_) return std::nullopt;
    return last_cmd_ms_ + kWatchdog_ms;
  }
  /// Counters of the host -> MCU decoder (corrupt frames, sequence gaps ...).
  const serial::DecoderCounters& rxCounters() const { return decoder_.counters(); }
  uint64_t framesSent() const { return frames_sent_; }
  uint64_t wheelCommandsApplied() const { return commands_applied_; }
  /// Last PTZ set-point received (pan, tilt in 0.1 mrad; home resets to 0/0).
  serial::PtzCommand ptz() const { return ptz_; }

 private:
  void apply(const serial::Message& msg, uint8_t seq, uint64_t now_ms);
  void applyWheel(const serial::WheelCommand& c, uint8_t seq, uint64_t now_ms);
  void event(uint64_t now_ms, std::string_view name, std::string_view detail);

  double max_wheel_rad_s_;
  std::size_t gas_channels_;  // configured gas channels (frame slots in use)
  bool gas_fault_ = false;
  double speed_noise_rad_s_;
  double heading_noise_rad_;
  SimObserver* observer_;
  std::mt19937_64 rng_;
  serial::FrameDecoder decoder_;
  serial::FrameEncoder encoder_;

  control::WheelSpeeds setpoint_;
  uint64_t last_cmd_ms_ = 0;        // boot counts as the last command
  uint64_t last_heartbeat_ms_ = 0;  // boot counts as the last heartbeat
  bool watchdog_tripped_ = false;
  bool host_silent_ = false;
  uint8_t cmd_seq_echo_ = 0;
  serial::PtzCommand ptz_;
  uint16_t battery_mv_ = kBatteryStart_mv;
  uint64_t frames_sent_ = 0;
  uint64_t commands_applied_ = 0;
};

}  // namespace inspect::sim
