#pragma once
// The MCU firmware's logic, the same on the real STM32, in QEMU and in host
// tests (docs/firmware.md): pure, no heap, no exceptions, no I/O; the board
// (firmware/boards/) reads the peripherals into PeripheralInputs every 1 ms,
// calls tick(), drives what PeripheralOutputs says and moves bytes between
// the UART and receive()/takeTx().
//
// What it does is docs/serial-protocol.md's MCU side, through shared/serial's
// codec (the one the Pi and the simulator use): a SensorFrame every 10 ms;
// wheel set-points from WheelCommands (ENABLE, clamped to the wheel-speed
// limit) into a speed loop per wheel; the 200 ms wheel-command watchdog
// (WATCHDOG, motors braked) and HOST_SILENT after 500 ms without a Heartbeat;
// the e-stop button (ESTOP_BUTTON, motors braked while it is pressed) and the
// drivers' fault line (MOTOR_DRIVER, braked); its own anti-collision stop
// (OBSTACLE_STOP); the ultrasonic sensors in turn (ULTRASONIC); gas channels
// (GAS_SENSOR); the battery (BATTERY_LOW); the camera mount's servos.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "firmware/core/analog_inputs.hpp"
#include "firmware/core/mcu_settings.hpp"
#include "firmware/core/odometry.hpp"
#include "firmware/core/ptz_servo.hpp"
#include "firmware/core/ultrasonic.hpp"
#include "firmware/core/wheel_speed.hpp"
#include "shared/serial/frame_codec.hpp"

namespace inspect::firmware {

/// What the board read this period.
struct PeripheralInputs {
  std::array<uint16_t, 2> encoder{};  // the left and right encoder timers' counters
  EchoCapture echo;                   // the echo of the sensor fired in the slot that ends now
  std::array<uint16_t, serial::kGasChannels> gas_adc{};  // ADC counts of the gas channels, in slot order
  uint16_t battery_adc = 0;
  uint8_t grayscale = 0;              // bit i = line sensor channel i sees a line
  bool estop_pressed = false;         // the button's contact, raw
  bool motor_driver_fault = false;    // the drivers' fault line
};

/// What the board drives this period.
struct PeripheralOutputs {
  std::array<float, 2> duty{};  // PWM duty, [-1, 1], left and right (sign = direction)
  bool brake = true;            // short the motors (standstill), duty 0
  int trigger = -1;             // the ultrasonic sensor to trigger now (0-3), -1 none
  std::array<uint16_t, 2> servo_us{PtzServo::kCentreUs, PtzServo::kCentreUs};  // pan, tilt pulses
};

/// Every frame the firmware dropped or could not send, by cause.
struct LinkCounters {
  serial::DecoderCounters rx;     // from the Pi: bad_cobs, bad_crc, bad_length, unknown_id, overflow, seq_gaps
  uint32_t rx_ignored = 0;        // valid frames of a message the MCU does not take (a SensorFrame)
  uint32_t tx_overruns = 0;       // sensor frames not sent: the UART had not drained the last ones
  uint32_t frames_sent = 0;
  uint32_t wheel_commands = 0;    // applied
  uint32_t watchdog_trips = 0;
};

class FirmwareCore {
 public:
  static constexpr float kPeriodS = 0.001f;  // tick() every 1 ms
  static constexpr std::size_t kTxBuffer = 256;

  explicit FirmwareCore(const McuSettings& s);
  FirmwareCore(const FirmwareCore&) = delete;
  FirmwareCore& operator=(const FirmwareCore&) = delete;

  /// Bytes from the Pi, received by `now_ms`. Corrupt frames are only counted.
  void receive(std::span<const uint8_t> bytes, uint32_t now_ms);
  /// One control period at `now_ms` (ms since boot, wrapping).
  PeripheralOutputs tick(uint32_t now_ms, const PeripheralInputs& in);
  /// Moves up to out.size() bytes of sensor frames to `out`; how many.
  std::size_t takeTx(std::span<uint8_t> out);
  std::size_t txPending() const { return tx_len_; }

  const McuSettings& settings() const { return s_; }
  /// McuFault bits now.
  uint16_t faults() const;
  /// The last sensor frame built.
  const serial::SensorFrame& lastFrame() const { return frame_; }
  const LinkCounters& counters() const { return counters_; }
  /// Wheel set-points in force (rad/s, after the clamp, the watchdog and the obstacle stop).
  std::array<float, 2> setpoints() const { return applied_; }
  const WheelSpeedLoop& wheel(int i) const { return i == 0 ? left_ : right_; }
  const PtzServo& ptz() const { return ptz_; }

 private:
  void apply(const serial::Message& msg, uint8_t seq, uint32_t now_ms);
  void sendFrame(uint32_t now_ms, const PeripheralInputs& in);

  const McuSettings& s_;
  serial::FrameDecoder decoder_;
  serial::FrameEncoder encoder_;
  WheelSpeedLoop left_, right_;
  Odometry odometry_;
  UltrasonicScheduler ultrasonic_;
  ObstacleStop obstacle_;
  BatteryMonitor battery_;
  Debounced estop_{McuSettings::kEStopDebounceMs};
  PtzServo ptz_;

  std::array<float, 2> commanded_{};  // the last WheelCommand's set-points, rad/s
  bool enabled_ = false;              // its ENABLE bit
  std::array<float, 2> applied_{};
  uint32_t last_cmd_ms_ = 0;          // boot counts as the last command and heartbeat
  uint32_t last_heartbeat_ms_ = 0;
  bool watchdog_ = false;
  bool host_silent_ = false;
  bool motor_fault_ = false;
  bool gas_fault_ = false;
  uint8_t cmd_seq_echo_ = 0;
  uint32_t next_frame_ms_ = 0;
  bool booted_ = false;
  serial::SensorFrame frame_;
  LinkCounters counters_;
  std::array<uint8_t, kTxBuffer> tx_{};
  std::size_t tx_len_ = 0;
};

}  // namespace inspect::firmware
