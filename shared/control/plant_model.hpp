#pragma once
// The hub-motor plant as the tuner and the simulator see it: each wheel a
// first-order lag with a static gain, a dead time and a saturation,
//   w(t) = G(s) u(t),  G(s) = gain e^(-dead_time s) / (time_constant s + 1),
// with the set-point clamped to +-saturation_rad_s before the lag.
// The nominal plant comes from config/robot.yaml (gain 1, no dead time);
// `identify` fits one from a recorded run (pc_server/tuning/plant_id.hpp);
// a simulated world may give the robot a different true plant (its `plant:`
// section, docs/world-format.md).
#include <cmath>
#include <algorithm>
#include <cstddef>
#include <deque>
#include <string>

#include "shared/control/diff_drive.hpp"

namespace inspect::control {

struct WheelMotorModel {
  double gain = 1.0;               // steady-state speed / set-point, [0.2, 5]
  double time_constant_s = 0.20;   // first-order lag, [0.001, 5] s
  double dead_time_s = 0.0;        // transport delay of the set-point, [0, 1] s
  double saturation_rad_s = 5.0;   // |set-point| limit, (0, 100] rad/s
};

struct PlantModel {
  WheelMotorModel left;
  WheelMotorModel right;
};

/// "" when the model is usable, else what is wrong (names the wheel and field).
inline std::string validatePlant(const PlantModel& p) {
  const auto check = [](const char* wheel, const WheelMotorModel& m) -> std::string {
    const std::string w = wheel;
    if (!std::isfinite(m.gain) || m.gain < 0.2 || m.gain > 5.0) return w + ".gain must be in [0.2, 5]";
    if (!std::isfinite(m.time_constant_s) || m.time_constant_s < 0.001 || m.time_constant_s > 5.0)
      return w + ".time_constant_s must be in [0.001, 5]";
    if (!std::isfinite(m.dead_time_s) || m.dead_time_s < 0.0 || m.dead_time_s > 1.0)
      return w + ".dead_time_s must be in [0, 1]";
    if (!std::isfinite(m.saturation_rad_s) || m.saturation_rad_s <= 0.0 || m.saturation_rad_s > 100.0)
      return w + ".saturation_rad_s must be in (0, 100]";
    return "";
  };
  if (auto e = check("left", p.left); !e.empty()) return e;
  return check("right", p.right);
}

/// Transport delay of wheel set-points: what the motors see at time t is the
/// set-point given at t - dead_time (zero before any). Times must not go back.
class SetpointDelay {
 public:
  SetpointDelay() = default;
  SetpointDelay(double dead_left_s, double dead_right_s) : dead_{dead_left_s, dead_right_s} {}

  /// Records the set-point given at t_s and returns the delayed one in force at t_s.
  WheelSpeeds apply(double t_s, const WheelSpeeds& sp) {
    if (dead_[0] <= 0.0 && dead_[1] <= 0.0) return sp;
    if (hist_.empty() || hist_.back().sp.left_rad_s != sp.left_rad_s || hist_.back().sp.right_rad_s != sp.right_rad_s)
      hist_.push_back({t_s, sp});
    WheelSpeeds out{valueAt(t_s - dead_[0]).left_rad_s, valueAt(t_s - dead_[1]).right_rad_s};
    // Forget entries older than the one in force for the longer delay.
    const double keep_from = t_s - std::max(dead_[0], dead_[1]);
    while (hist_.size() > 1 && hist_[1].t_s <= keep_from) hist_.pop_front();
    return out;
  }

 private:
  struct Entry {
    double t_s;
    WheelSpeeds sp;
  };
  WheelSpeeds valueAt(double t_s) const {
    WheelSpeeds v{};
    for (const auto& e : hist_) {
      if (e.t_s > t_s + 1e-12) break;
      v = e.sp;
    }
    return v;
  }
  double dead_[2] = {0.0, 0.0};
  std::deque<Entry> hist_;
};

}  // namespace inspect::control
