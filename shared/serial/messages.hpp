#pragma once
// Messages of the robot_client <-> MCU serial protocol (docs/serial-protocol.md).
// Fields hold the exact wire integers; the unit is in each name.
#include <array>
#include <cstdint>
#include <variant>

namespace inspect::serial {

/// Message ids (first byte of a decoded frame).
enum class MsgId : uint8_t {
  kSensorFrame = 0x10,   // MCU -> Pi, 100 Hz
  kWheelCommand = 0x20,  // Pi -> MCU
  kHeartbeat = 0x21,     // Pi -> MCU
  kPtzCommand = 0x22,    // Pi -> MCU
};

/// Ultrasonic channel order in SensorFrame::ultrasonic_mm.
enum UltrasonicIndex : int { kFrontLeft = 0, kFrontRight = 1, kLeft = 2, kRight = 3, kUltrasonicCount = 4 };
/// Number of gas channels carried in a sensor frame.
inline constexpr int kGasChannels = 4;
/// Ultrasonic value meaning "no echo within range".
inline constexpr uint16_t kNoEcho = 0xFFFF;
/// Gas slot value meaning "the sensor gives no data" (0..0xFFFE are readings).
inline constexpr uint16_t kGasNoData = 0xFFFF;

/// MCU fault flag bits (SensorFrame::faults).
enum McuFault : uint16_t {
  kFaultWatchdog = 1u << 0,        // no valid wheel command for 200 ms: motors stopped
  kFaultUltrasonic = 1u << 1,      // an ultrasonic sensor failed to answer
  kFaultGasSensor = 1u << 2,       // a gas sensor reports a fault
  kFaultBatteryLow = 1u << 3,      // battery below the low threshold
  kFaultMotorDriver = 1u << 4,     // hub-motor driver fault
  kFaultEStopButton = 1u << 5,     // the robot's own e-stop button is pressed
  kFaultHostSilent = 1u << 6,      // no heartbeat from the Pi for 500 ms
  kFaultObstacleStop = 1u << 7,    // the MCU's own anti-collision stop is active
};

/// MCU -> Pi sensor frame, sent at 100 Hz. Payload 40 bytes.
struct SensorFrame {
  uint32_t mcu_time_ms = 0;                        // MCU uptime
  std::array<int16_t, 2> wheel_speed_mrad_s{};     // measured angular speed, left, right
  std::array<int32_t, 2> wheel_disp_0p1mm{};       // cumulative wheel travel, wraps
  int16_t heading_0p1mrad = 0;                     // heading, CCW positive, [-31416, 31416]
  std::array<uint16_t, kUltrasonicCount> ultrasonic_mm{};  // kNoEcho = nothing in range
  uint8_t grayscale = 0;                           // bit i = channel i over a line
  std::array<uint16_t, kGasChannels> gas_raw{};    // value = raw * channel scale (config)
  uint16_t battery_mv = 0;
  uint16_t faults = 0;                             // McuFault bits
  uint8_t cmd_seq_echo = 0;                        // sequence number of the last applied wheel command
  bool operator==(const SensorFrame&) const = default;
};

/// Pi -> MCU wheel speed set-points. Payload 5 bytes.
struct WheelCommand {
  int16_t left_mrad_s = 0;
  int16_t right_mrad_s = 0;
  uint8_t flags = 0;  // bit 0: drive enable (0 = brake to standstill)
  static constexpr uint8_t kEnable = 0x01;
  bool operator==(const WheelCommand&) const = default;
};

/// Pi -> MCU liveness signal. Payload 4 bytes.
struct Heartbeat {
  uint32_t host_time_ms = 0;
  bool operator==(const Heartbeat&) const = default;
};

/// Pi -> MCU camera mount set-point. Payload 5 bytes.
struct PtzCommand {
  int16_t pan_0p1mrad = 0;   // CCW positive
  int16_t tilt_0p1mrad = 0;  // up positive
  uint8_t flags = 0;         // bit 0: home (ignore pan/tilt, go to 0/0)
  bool operator==(const PtzCommand&) const = default;
};

using Message = std::variant<SensorFrame, WheelCommand, Heartbeat, PtzCommand>;

/// Payload sizes in bytes (everything between sequence number and CRC).
inline constexpr std::size_t kSensorFramePayload = 40;
inline constexpr std::size_t kWheelCommandPayload = 5;
inline constexpr std::size_t kHeartbeatPayload = 4;
inline constexpr std::size_t kPtzCommandPayload = 5;

}  // namespace inspect::serial
