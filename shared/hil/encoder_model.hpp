// The QEMU board's encoder timers between the simulator's samples
// (docs/firmware.md "Hardware in the loop"). A real encoder timer counts on
// its own; over the HIL link its counts come as HilEncoders samples, every
// 10 ms when the link flows, but the simulator-to-board direction of a pty
// stalls for 40-150 ms on a loaded host (the kernel's tty work item, QEMU
// taking one byte at a time). Carried on at the sample's rate alone, a wheel
// that had just been told to speed up read as one that had not: its counts
// froze for a step from rest, the firmware's PI wound up on the error, and
// the next sample came as a jump (frames' speed 0 then -10 rad/s on a
// -2 rad/s step). Here the sample is carried on by the motor the simulator
// models: its speed tends toward duty / speed_ff through the first order of
// the robot's motor time constant, with the duties this board drives, which
// reach the simulator within milliseconds (that direction does not stall).
// This is the board's emulation of a peripheral, like QEMU's own: the
// firmware's core still reads a counter and differences it.
#pragma once

#include <array>
#include <cstdint>

#include "shared/control/first_order.hpp"
#include "shared/hil/hil_link.hpp"

namespace inspect::hil {

class HilEncoderModel {
 public:
  /// A sample is carried on this far past its board_ms at most: a link that
  /// stopped. (200 ms: a starved link delivered samples over 50 ms old, and
  /// counts that stopped there read as a wheel that stopped.)
  static constexpr int32_t kMaxExtrapolationMs = 200;

  /// `speed_ff`: duty per rad/s of the motor (McuSettings::speed_ff); `tau_s`:
  /// its time constant (McuSettings::response_tau_s); `counts_per_rev`: the encoder's.
  HilEncoderModel(float speed_ff, float tau_s, uint32_t counts_per_rev)
      : counts_s_per_duty_(speed_ff > 0.0f ? static_cast<float>(counts_per_rev) / (6.28318530718f * speed_ff) : 0.0f),
        tau_ms_(tau_s * 1000.0f) {}

  /// The simulator's newest sample: from now on the counts follow from it.
  void take(const HilEncoders& e) {
    sample_ = e;
    for (std::size_t i = 0; i < 2; ++i) {
      wheel_[i].counts = 0.0f;
      wheel_[i].rate = static_cast<float>(e.rate_counts_s[i]);
    }
    at_ms_ = e.board_ms;
    taken_ = true;
  }

  /// The duties driven from now on (brake: 0), which the simulator's motors tend to.
  void drive(const std::array<float, 2>& duty) { duty_ = duty; }

  /// The counters at the board's `now_ms` (a tick's due time).
  std::array<uint16_t, 2> countersAt(uint32_t now_ms) {
    std::array<uint16_t, 2> c = sample_.counter;
    if (!taken_) return c;
    // Since the model last moved; negative when the sample is newer than this
    // tick (a late tick catching up): back along the rate alone. At most
    // kMaxExtrapolationMs past the sample.
    const auto since_sample = static_cast<int16_t>(static_cast<uint16_t>(now_ms - sample_.board_ms));
    constexpr int32_t kMax = kMaxExtrapolationMs;
    const int32_t limit = since_sample > kMax ? kMax : (since_sample < -kMax ? -kMax : since_sample);
    const auto moved_to = static_cast<int16_t>(static_cast<uint16_t>(at_ms_ - sample_.board_ms));
    const auto dt_ms = static_cast<float>(limit - moved_to);
    for (std::size_t i = 0; i < 2; ++i) {
      Wheel& w = wheel_[i];
      if (dt_ms < 0.0f || tau_ms_ <= 0.0f) {
        w.counts += w.rate * dt_ms / 1000.0f;
      } else if (dt_ms > 0.0f) {
        // The exact step of the simulator's motor (sim/robot_plant), in ms.
        const auto s = control::firstOrderStep(w.rate, duty_[i] * counts_s_per_duty_, tau_ms_, dt_ms);
        w.counts += s.integral / 1000.0f;
        w.rate = s.value;
      }
      const float r = w.counts + (w.counts < 0.0f ? -0.5f : 0.5f);
      c[i] = static_cast<uint16_t>(c[i] + static_cast<uint16_t>(static_cast<int32_t>(r)));
    }
    at_ms_ = static_cast<uint16_t>(sample_.board_ms + limit);
    return c;
  }

 private:
  struct Wheel {
    float counts = 0.0f;  // since the sample's counter
    float rate = 0.0f;    // counts per second
  };
  float counts_s_per_duty_;
  float tau_ms_;
  HilEncoders sample_;
  std::array<Wheel, 2> wheel_{};
  std::array<float, 2> duty_{};
  uint16_t at_ms_ = 0;  // board ms (low bits) the model has moved to
  bool taken_ = false;
};

}  // namespace inspect::hil
