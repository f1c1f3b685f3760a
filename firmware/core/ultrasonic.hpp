#pragma once
// The four ultrasonic sensors (HC-SR04-like: a trigger pulse, then an echo
// pulse as long as the sound's way there and back), fired in turn, one per
// slot, so that none hears another's ping: front-left, front-right, left,
// right. At the end of its slot the board's input capture says whether the
// echo pulse rose, and its width: width x 343 m/s / 2 is the range; no fall
// within the slot, or a range beyond max_range_m, is "no echo" (0xFFFF); an
// echo pulse that never rose for ultrasonic_missed_limit slots in a row is a
// sensor that does not answer (ULTRASONIC, its range 0xFFFF until it does).
#include <array>
#include <cstdint>

#include "firmware/core/mcu_settings.hpp"
#include "shared/serial/messages.hpp"

namespace inspect::firmware {

/// What the input capture saw of the echo line since the slot's trigger.
struct EchoCapture {
  bool rose = false;      // the echo pulse started
  bool fell = false;      // ... and ended
  uint32_t width_us = 0;  // its width, when it fell
};

class UltrasonicScheduler {
 public:
  explicit UltrasonicScheduler(const McuSettings& s) : s_(s) {}

  /// Every ms: the sensor to trigger now (serial::UltrasonicIndex), or -1. `capture` is the echo
  /// of the sensor fired in the slot that ends now (read when a slot ends).
  int tick(uint32_t now_ms, const EchoCapture& capture);

  std::array<uint16_t, serial::kUltrasonicCount> rangesMm() const { return ranges_; }
  /// Some sensor does not answer (ULTRASONIC).
  bool fault() const;
  /// Slots completed per sensor (its readings).
  const std::array<uint32_t, serial::kUltrasonicCount>& readings() const { return readings_; }

 private:
  uint16_t toMm(const EchoCapture& c) const;
  const McuSettings& s_;
  bool started_ = false;
  uint32_t slot_start_ms_ = 0;
  int current_ = -1;  // the sensor fired in the running slot
  std::array<uint16_t, serial::kUltrasonicCount> ranges_{serial::kNoEcho, serial::kNoEcho, serial::kNoEcho,
                                                        serial::kNoEcho};
  std::array<uint8_t, serial::kUltrasonicCount> missed_{};
  std::array<uint32_t, serial::kUltrasonicCount> readings_{};
};

/// The MCU's own anti-collision stop: active from a front range under
/// obstacle_stop_m until both front ranges are above obstacle_clear_m; while
/// active, the wheels' common (forward) part of a set-point is cut to zero or
/// less, their difference (turning) kept: the robot may turn and back away.
class ObstacleStop {
 public:
  explicit ObstacleStop(const McuSettings& s) : s_(s) {}
  /// The front-left and front-right ranges, mm (0xFFFF = nothing in range).
  void update(uint16_t front_left_mm, uint16_t front_right_mm);
  bool active() const { return active_; }
  /// The wheel set-points (rad/s) with no forward motion while active.
  void limit(float& left_rad_s, float& right_rad_s) const;

 private:
  const McuSettings& s_;
  bool active_ = false;
};

}  // namespace inspect::firmware
