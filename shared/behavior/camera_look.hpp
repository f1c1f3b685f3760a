#pragma once
// One camera picture's people as the people tracker takes them
// (docs/human-awareness.md, "Fusion"): each person a bearing from the lens
// and, when the feet were in view, a range along the floor; and where the
// camera looked (so that a tracked object inside the view that the detector
// did not find counts against it being a person). Plain data: the robot
// fills it from the people watcher, the arena from its detector model.
#include <array>
#include <cstddef>

namespace inspect::behavior {

/// One person in one picture, robot frame, from the lens.
struct CameraPerson {
  double bearing_rad = 0.0;  // counter-clockwise from the robot's heading
  double range_m = -1.0;     // along the floor to the feet; < 0 = feet not in view
};

/// Where the camera looked for one picture, and whom it found.
struct CameraLook {
  static constexpr std::size_t kMaxPeople = 8;
  double lens_x_m = 0.20, lens_y_m = 0.0;  // the lens in the robot frame
  double axis_rad = 0.0;                    // the optical axis (PTZ pan), robot frame
  double half_fov_rad = 0.5235987755982988; // half the horizontal field of view
  bool wide = false;                        // the wide, fixed head (its own recall by distance), else the PTZ head
  std::array<CameraPerson, kMaxPeople> people{};
  std::size_t count = 0;
  bool add(const CameraPerson& p) {
    if (count >= kMaxPeople) return false;
    people[count++] = p;
    return true;
  }
};

/// A detector's recall by distance from the lens: recall[i] for distances up
/// to upto_m[i], 0 beyond the last.
struct RecallTable {
  std::array<double, 5> upto_m{};
  std::array<double, 5> recall{};
  double at(double d_m) const {
    for (std::size_t i = 0; i < upto_m.size(); ++i)
      if (d_m <= upto_m[i]) return recall[i];
    return 0.0;
  }
};

/// How the tracker weighs the camera (config/behavior.yaml `tracker.camera`).
/// Each track keeps the log-odds that it is a person: a detection adds
/// hit_logodds (the detector's precision), a picture that should have shown
/// it and did not adds ln(1 - recall at its distance) (bench_people's recall
/// by distance), so a sonar echo the camera looks at and never confirms
/// stops counting as a person at deny_logodds.
struct CameraFusionParams {
  bool enabled = true;
  double bearing_sigma_deg = 0.5;   // detection box centre (bench: p90 0.35 deg) and the picture's latency
  double range_sigma_frac = 0.25;   // foot-row range (bench: p50 12 %, p90 44 %)
  double range_bias_frac = 0.107;   // the foot-row range reads this much long (bench: signed p50 +10.7 %); divided out
  double gate_chi2 = 13.8;          // association gate on the normalised innovation (99.9 %, 2 dof)
  double hit_logodds = 2.5;         // a detection (precision ~0.94: ln(0.94 / 0.06) = 2.75, a little less)
  double person_logodds = 2.0;      // a camera-confirmed track at or above this is a person, moving or not
  double deny_logodds = -2.5;       // a track at or below this is not a person, whatever its motion
  double doubt_logodds = -0.5;      // a track the camera never found, at or below this, is not a person yet
  double max_logodds = 6.0;         // evidence saturates both ways
  int confirm_hits = 3;             // detections to confirm a camera-only track (within tracker.confirm_window_s)
  double bearing_hold_s = 1.0;      // this long after a detection, a track's echoes give it range only
  double max_new_range_m = 10.0;    // new tracks only from detections this close
  double edge_margin_deg = 3.0;     // a track this near the picture's edge is not counted as missed
  double occluder_width_m = 0.6;    // a closer track within this width on the same bearing hides a track
  // Recall by distance from the lens, one table per head: the bench's 640x480
  // HOG figures for the PTZ head, bench_people --head wide's 480x360 HOG
  // (one window agreeing) for the wide head.
  RecallTable recall{{3.0, 4.0, 6.0, 8.0, 10.0}, {0.0, 0.34, 0.55, 0.65, 0.45}};
  RecallTable wide_recall{{1.0, 1.5, 2.0, 3.0, 4.0}, {0.06, 0.41, 0.70, 0.57, 0.07}};
  double recallAt(double d_m, bool wide = false) const { return (wide ? wide_recall : recall).at(d_m); }
};

}  // namespace inspect::behavior
