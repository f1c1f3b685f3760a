#pragma once
// Open-loop wheel set-point profiles for plant identification (`identify`):
// holds, steps and linear chirps on the two wheels, one segment after the
// other. The robot plays one (Command.wheel_test, docs/tuning.md) and sends
// at(t) to the MCU each tick; the server fits the hub-motor model to the
// recorded command and measured wheel speeds. Pure: time is an argument.
#include <string>
#include <vector>

#include "shared/control/diff_drive.hpp"

namespace inspect::control {

struct WheelProfileSegment {
  enum class Kind { kHold, kStep, kChirp };
  Kind kind = Kind::kHold;
  double duration_s = 0.0;   // > 0
  double left_rad_s = 0.0;   // step: the level; chirp: the amplitude (signed); hold: ignored (0)
  double right_rad_s = 0.0;
  double f0_hz = 0.0;        // chirp: frequency at the start and the end of the segment (linear sweep)
  double f1_hz = 0.0;
};

const char* toString(WheelProfileSegment::Kind k);

class WheelProfile {
 public:
  /// Throws std::invalid_argument naming the segment (1-based) and the
  /// problem: no segments, duration not in (0, 600], a level or amplitude
  /// beyond max_wheel_rad_s or not finite, chirp frequencies not in (0, 20] Hz.
  WheelProfile(std::vector<WheelProfileSegment> segments, double max_wheel_rad_s);

  double duration_s() const { return duration_s_; }
  /// The set-point at t (seconds from the start); zero before 0 and after the end.
  WheelSpeeds at(double t_s) const;
  const std::vector<WheelProfileSegment>& segments() const { return segs_; }

  /// The standard identification run: steps of +-amplitude and chirps of
  /// 0.1..3 Hz, with the wheels turning in opposite directions so that the
  /// robot spins on its spot (safe in a narrow aisle), plus one short
  /// same-direction step pair that returns the robot to where it started.
  static WheelProfile standardIdentification(double amplitude_rad_s, double max_wheel_rad_s);

 private:
  std::vector<WheelProfileSegment> segs_;
  std::vector<double> start_s_;  // start time of each segment
  double duration_s_ = 0.0;
};

}  // namespace inspect::control
