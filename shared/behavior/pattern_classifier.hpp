#pragma once
// Behaviour pattern of a tracked person relative to the robot (paper Table 1):
// crossing (moves across the robot's path), encountering (comes towards the
// robot, laterally offset), leading (ahead, same direction), confronting
// (directly ahead, opposite direction), or none (behind, standing, far to the
// side). Decided from the relative position, relative heading and speed, with
// angle hysteresis bands and a minimum dwell before a change, so the output
// does not flicker on a noisy track. Pure state + step(dt).
#include <cstdint>

#include "shared/behavior/behavior_pattern.hpp"
#include "shared/control/diff_drive.hpp"

namespace inspect::behavior {

// Defaults follow the arena's ground truth (docs/scenarios.md, "Ground truth"):
// crossing for relative headings in (30, 150) deg, leading / confronting on the
// robot's path (|lateral| within its body plus a person's, 0.6 m), encountering
// beside it, nobody behind the axle.
struct PatternParams {
  double min_speed_m_s = 0.15;      // slower people have no pattern (none)
  double behind_m = 0.0;            // relative x below this: behind the robot, none
  double crossing_deg = 30;         // |relative heading| within 90 +- (90 - this) is crossing
  double along_deg = 25;            // within this of 0 / 180 deg: same / opposite direction
  double confront_lateral_m = 0.6;  // |lateral offset| below: on the robot's path (confronting when opposite,
                                    // leading when the same direction); beside it: encountering / none
  double max_lateral_m = 2.0;       // beyond this lateral offset same/opposite movers are none
  double dwell_s = 0.3;             // a new pattern must hold this long before it is reported
};

/// The raw (un-debounced) pattern of a person at relative position/velocity.
/// `rel_x`, `rel_y`: person in the robot frame (x ahead, y left); `vx`, `vy`:
/// its velocity in the robot's heading frame (world velocity rotated by -theta).
/// Returns kNone inside hysteresis gaps when `previous` is kNone, else keeps `previous` there.
Pattern rawPattern(double rel_x, double rel_y, double vx, double vy, Pattern previous, const PatternParams& p);

class PatternClassifier {
 public:
  explicit PatternClassifier(const PatternParams& p = {}) : p_(p) {}
  /// One tick with the person's world position/velocity and the robot's pose.
  Pattern step(const control::Pose2& robot, double px, double py, double vx, double vy, double dt_s);
  /// No person: decays to kNone after the dwell.
  Pattern stepNone(double dt_s);
  Pattern current() const { return current_; }
  uint64_t switches() const { return switches_; }
  void reset() {
    current_ = candidate_ = Pattern::kNone;
    held_s_ = 0;
  }

 private:
  Pattern debounce(Pattern raw, double dt_s);
  PatternParams p_;
  Pattern current_ = Pattern::kNone;
  Pattern candidate_ = Pattern::kNone;
  double held_s_ = 0;
  uint64_t switches_ = 0;
};

}  // namespace inspect::behavior
