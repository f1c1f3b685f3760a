#pragma once
// The hardware-in-the-loop link (docs/firmware.md): the second serial line
// between the firmware's QEMU board (its USART2) and `mcu_sim --hil`, which
// stands in for the peripherals QEMU does not emulate. The simulator sends what
// the peripherals would read (HilEncoders at 500 Hz, HilSensors at 50 Hz and at
// each ping's answer); the board sends what it drives (HilOutputs, every 2 ms). Framed as the Pi's protocol is
// (shared/serial: id, seq, payload, CRC-16, COBS, 0x00) with ids of its own.
// No I/O and no allocation: it builds for the MCU too.
#include <array>
#include <cstdint>
#include <span>
#include <variant>

#include "shared/serial/frame_codec.hpp"
#include "shared/serial/messages.hpp"

namespace inspect::hil {

enum class HilId : uint8_t {
  kEncoders = 0x80,  // simulator -> board, every 10 ms
  kOutputs = 0x81,   // board -> simulator
  kSensors = 0x82,   // simulator -> board, every 20 ms and at each ping's answer
};

/// Simulator -> board, every 10 ms (100 Hz): the encoder timers' counters at
/// one instant of the board's clock, and how fast they count. The board reads
/// its counters at each control tick's due time from the latest of them
/// (HilEncoderModel, shared/hil/encoder_model.hpp), as a real encoder timer is
/// read: a count that arrived late over the link (QEMU takes a pty's bytes one
/// at a time, about 9 KB/s here, and its vCPU is not always run) is then still
/// the count of the tick's instant, not of whenever it came. Without this the
/// speed loop's 20 ms estimate saw counts 2-4 ms old by uneven amounts
/// (docs/firmware.md). Payload 14 bytes.
struct HilEncoders {
  std::array<uint16_t, 2> counter{};        // left, right (wrapping), at board_ms
  std::array<int32_t, 2> rate_counts_s{};   // their rates now, counts per second
  uint16_t board_ms = 0;                    // the board's clock (HilOutputs::mcu_time_ms, low 16 bits)
                                            // at which they were read, as the simulator maps its time to it
  bool operator==(const HilEncoders&) const = default;
};

/// Simulator -> board: what the other peripherals read now. Payload 18 bytes.
struct HilSensors {
  uint8_t echo_count = 0;             // the HilOutputs::trigger_count of the ping this echo answers
  uint8_t echo_flags = 0;             // kEchoRose, kEchoFell
  uint32_t echo_width_us = 0;         // the echo pulse's width, when it fell
  std::array<uint16_t, serial::kGasChannels> gas_adc{};
  uint16_t battery_adc = 0;
  uint8_t grayscale = 0;              // bit i = line sensor channel i over a line
  uint8_t switches = 0;               // kEStopPressed, kDriverFault
  static constexpr uint8_t kEchoRose = 0x01;
  static constexpr uint8_t kEchoFell = 0x02;
  static constexpr uint8_t kEStopPressed = 0x01;
  static constexpr uint8_t kDriverFault = 0x02;
  bool operator==(const HilSensors&) const = default;
};

/// Board -> simulator: what the firmware drives. Payload 26 bytes.
struct HilOutputs {
  uint32_t mcu_time_ms = 0;           // the firmware's clock (TIM2)
  std::array<int16_t, 2> duty_1e4{};  // PWM duty x 10000, left, right; the sign is the direction
  uint8_t flags = 0;                  // kBrake
  uint8_t trigger_sensor = 0;         // the sensor of the latest ping (serial::UltrasonicIndex)
  uint8_t trigger_count = 0;          // pings so far (wrapping): a new value is a new ping
  std::array<uint16_t, 2> servo_us{}; // pan, tilt servo pulses
  uint16_t tick_late_us = 0;          // how late the latest 1 ms control tick started (TIM2), us
  uint8_t input_seq = 0;              // the seq of the last simulator frame the board took: the
                                      // simulator keeps few in flight, so none waits in a queue
  std::array<int16_t, 2> setpoint_mrad_s{};  // the wheel set-points in force (after the clamp, the
                                             // watchdog, the obstacle stop; before the speed loop's
                                             // slew): the ground truth logs them
  std::array<int16_t, 2> ptz_target_0p1mrad{};  // the camera mount's target from the last PtzCommand
                                                // (pan, tilt; the truth log's ptz events)
  static constexpr uint8_t kBrake = 0x01;
  bool operator==(const HilOutputs&) const = default;
};

inline constexpr std::size_t kHilEncodersPayload = 14;
inline constexpr std::size_t kHilSensorsPayload = 18;
inline constexpr std::size_t kHilOutputsPayload = 26;

using HilMessage = std::variant<HilEncoders, HilSensors, HilOutputs>;

/// One message as a frame for the wire (`seq` the sender's count).
serial::EncodedFrame encodeHil(const HilMessage& msg, uint8_t seq);
/// One frame (COBS bytes without delimiter): kNone with `msg` and its `seq`, or why it was dropped.
serial::FrameError decodeHil(std::span<const uint8_t> cobs_bytes, HilMessage& msg, uint8_t& seq);

/// Streaming decoder of the HIL link, resynchronising on 0x00.
class HilDecoder {
 public:
  /// on_message(const HilMessage&, uint8_t seq) for each valid frame.
  template <class F>
  void feed(std::span<const uint8_t> bytes, F&& on_message) {
    assembler_.feed(
        bytes,
        [&](std::span<const uint8_t> frame) {
          HilMessage msg;
          uint8_t seq = 0;
          if (decodeHil(frame, msg, seq) == serial::FrameError::kNone) {
            ++frames_ok_;
            on_message(msg, seq);
          } else {
            ++errors_;
          }
        },
        [&] { ++errors_; });
  }
  uint32_t framesOk() const { return frames_ok_; }
  uint32_t errors() const { return errors_; }

 private:
  serial::FrameAssembler assembler_;
  uint32_t frames_ok_ = 0;
  uint32_t errors_ = 0;
};

}  // namespace inspect::hil
