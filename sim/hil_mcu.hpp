#pragma once
// The MCU as the real firmware, hardware-in-the-loop (mcu_sim --hil,
// docs/firmware.md): in place of McuEmulator, the simulation stands in for
// the peripherals the firmware's QEMU board does not have. It reads the
// board's HilOutputs (shared/hil: PWM duty, brake, pings, servo pulses) and
// sends it the encoder counters every kInputPeriod_ms (HilEncoders: stamped
// with the board's clock, which it maps from its own by the HilOutputs'
// mcu_time_ms; with their rates, so that the board reads them at each
// tick's instant) and the
// other peripherals every kSensorPeriod_ms and at each ping's answer
// (HilSensors: the echo, gas and battery ADC counts, line bits, the switches).
// The motors: a DC motor per wheel, a first order toward the speed its duty
// drives it at without load (duty / mcu.speed_ff: 6.5 rad/s at full duty),
// with the plant's time constant; braked, toward 0. So the firmware's speed
// loop is what moves the robot. Pure: no I/O, time is an argument.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "firmware/core/mcu_settings.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/control/diff_drive.hpp"
#include "shared/hil/hil_link.hpp"
#include "shared/util/latency_histogram.hpp"
#include "sim/robot_plant.hpp"
#include "sim/sim_observer.hpp"

namespace inspect::sim {

class HilMcu {
 public:
  static constexpr uint64_t kInputPeriod_ms = 10;   // encoders, 100 Hz (the board carries them on between: HilEncoderModel)
  static constexpr uint64_t kPollPeriod_ms = 2;     // the board's outputs (500 Hz) taken and pings answered this often
  static constexpr uint64_t kSensorPeriod_ms = 20;  // the rest, 50 Hz (QEMU takes about 9 KB/s)
  /// Frames sent and not yet taken by the board (HilOutputs::input_seq) at
  /// most: QEMU takes a pty's bytes one at a time, slower than 500 frames a
  /// second when its host is busy, and a frame that waited in the pty's queue
  /// would give the firmware a stale encoder count. Beyond it the frame is not
  /// sent (the next one carries newer values: every field is absolute).
  static constexpr uint8_t kMaxInFlight = 2;
  /// A firmware control tick this late (TIM2) is a `late_tick` event in the truth log.
  static constexpr uint16_t kLateTickEvent_us = 5000;
  /// Below this the drivers' fault current (NAMUR NE 43: a failed transmitter's 2 mA).
  static constexpr float kFailedTransmitterMa = 2.0f;

  /// `observer` (may be null) gets the firmware's camera-mount targets as `ptz` events, as the emulator's.
  HilMcu(const config::RobotConfig& robot, SimObserver* observer);

  /// Bytes from the board's USART2 at now_ms.
  void receive(std::span<const uint8_t> bytes, uint64_t now_ms);
  /// The speeds the motors run toward now (rad/s), from the latest duty.
  control::WheelSpeeds motorTargets() const;
  /// The firmware's wheel set-points in force (rad/s; 0 before it speaks).
  control::WheelSpeeds firmwareSetpoints() const {
    return {last_.setpoint_mrad_s[0] / 1000.0, last_.setpoint_mrad_s[1] / 1000.0};
  }
  /// The camera mount's pan and tilt (rad) its servo pulses put it at (home before the board speaks).
  std::array<double, 2> ptzRad() const;
  /// The sensor of a ping not answered yet, or -1.
  int pendingPing() const { return answered_count_ != last_.trigger_count && heard_ ? last_.trigger_sensor : -1; }
  /// Answers it with the range the world gives (serial::kNoEcho: nothing in range).
  void answerPing(uint16_t range_mm);
  /// The encoder counters and rates of `truth` at now_ms, stamped with the board's clock, as a frame
  /// appended to tx, unless kMaxInFlight hold it back (no loss: the next carries newer counts).
  void sendEncoders(const PlantState& truth, uint64_t now_ms, std::vector<uint8_t>& tx);
  /// The board's clock minus ours (ms): from the least delayed HilOutputs so
  /// far, lowered only when a whole kClockWindow_ms of reports says it is more
  /// than kClockSlack_ms too high; 0 before the board speaks. Steady: each
  /// change shifts the counts the board reads by the wheel's rate x the change
  /// (one ms at 2 rad/s moved its 20 ms speed estimate by 0.1 rad/s).
  int64_t boardClockOffsetMs() const { return clock_offset_ms_; }
  static constexpr uint64_t kClockWindow_ms = 2000;
  static constexpr int64_t kClockSlack_ms = 2;
  /// Whether the other peripherals' readings are due at now_ms: every
  /// kSensorPeriod_ms, at once when the board first speaks and when a ping has
  /// been answered, and again at every step while the in-flight window holds
  /// them back (an answer held to the next period came after the firmware's
  /// 30 ms slot: a missed echo, ULTRASONIC under load).
  bool sensorsDue(uint64_t now_ms) const { return readings_due_ || now_ms % kSensorPeriod_ms == 0; }
  /// What the other peripherals read at now_ms, as a frame appended to tx.
  /// Held back by kMaxInFlight, they stay due (sensorsDue) and go at a later step.
  void sendSensors(uint64_t now_ms, uint8_t grayscale, const std::array<uint16_t, serial::kGasChannels>& gas_raw,
                   std::vector<uint8_t>& tx);

  bool heard() const { return heard_; }
  /// True once the board has taken a frame sent after it spoke (its input_seq
  /// acknowledges it): its peripherals read the world. QEMU reads a pty only
  /// once its 1 s poll has seen the other end open, so this came up to a
  /// second after heard(), the board reading the held-still world meanwhile.
  bool boardTookInputs() const { return inputs_taken_; }
  const hil::HilOutputs& lastOutputs() const { return last_; }
  uint32_t framesReceived() const { return decoder_.framesOk(); }
  uint32_t errors() const { return decoder_.errors(); }
  uint64_t framesSent() const { return frames_sent_; }
  uint64_t pings() const { return pings_; }
  /// Frames not sent (kMaxInFlight were in flight): encoder frames, and readings
  /// that had to wait (each once, however many steps it waited).
  uint64_t framesHeldBack() const { return held_back_; }
  /// How late the firmware's control ticks started (TIM2), from its reports.
  const util::LatencyHistogram& tickLateness() const { return late_; }

 private:
  firmware::McuSettings settings_;
  SimObserver* observer_;
  double wheel_radius_m_;
  hil::HilDecoder decoder_;
  hil::HilOutputs last_;
  bool heard_ = false;
  bool readings_due_ = false;   // due now (first contact, a ping's answer) or held back so far
  bool readings_held_ = false;  // the due readings were held back at least once (counted in held_back_)
  bool inputs_taken_ = false;
  uint8_t first_seq_ = 0;  // the seq of the first frame sent after the board spoke
  hil::HilSensors echo_;  // the echo fields of the answer to the latest ping
  uint8_t answered_count_ = 0;
  uint8_t seq_ = 0;
  uint8_t acked_seq_ = 0;  // the board's input_seq
  uint64_t frames_sent_ = 0;
  uint64_t held_back_ = 0;
  uint64_t pings_ = 0;
  util::LatencyHistogram late_;
  // The board's clock offset: the largest mcu_time_ms - now_ms (the least
  // delayed report), and this window's largest.
  int64_t clock_offset_ms_ = 0;
  bool clock_known_ = false;
  int64_t window_best_ = 0;
  uint64_t window_start_ms_ = 0;
  bool window_any_ = false;
  void trackBoardClock(uint32_t mcu_time_ms, uint64_t now_ms);

  bool append(const hil::HilMessage& m, std::vector<uint8_t>& tx);
};

}  // namespace inspect::sim
