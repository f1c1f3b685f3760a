#pragma once
// Active looking (issue 61; docs/human-awareness.md "Active looking"): the
// PTZ head turns toward a sonar track beside the robot that no head has
// settled (never detected, not yet doubted or denied), where the wide head
// cannot see it (beyond its half field of view) and the PTZ head's detector
// reaches (its recall there > 0), while nobody is ahead; it holds there for a
// few pictures and turns back ahead. Each track is looked at once per
// revisit period. Pure: a function of the tracks, the robot's pose and time,
// and the planner's own state (which track, since when).
#include <vector>

#include "shared/behavior/camera_look.hpp"
#include "shared/behavior/human_tracker.hpp"
#include "shared/control/diff_drive.hpp"

namespace inspect::behavior {

/// config/behavior.yaml `active_look`.
struct ActiveLookParams {
  bool enabled = true;
  double min_off_axis_deg = 55.0;  // a track at least this far off the heading (from the PTZ lens): the
                                   // wide head's 60 degrees less its edge margin
  double max_pan_deg = 110.0;      // the PTZ head's reach
  double dwell_s = 1.2;            // hold on a track this long (~5 pictures at 4-5 Hz), from when the head is there
  double slew_deg_s = 180.0;       // the head's turn rate: pictures while it turns are not taken
  double revisit_s = 6.0;          // a track looked at is not looked at again for this long
  double ahead_m = 4.0;            // nobody ahead: no person within this of the lens within ahead_deg
  double ahead_deg = 35.0;
};

/// The planner's state between ticks (a robot, an arena run).
struct ActiveLookState {
  int target_id = -1;           // the track looked at, -1 = looking ahead
  double pan_rad = 0.0;         // the pan asked now
  double settled_s = 0.0;       // when the head gets there (turning until then)
  double until_s = 0.0;         // when the look ends
  double off_path_s = 0.0;      // time asked off the path (|pan| beyond the PTZ half field of view), summed
  double last_s = -1.0;         // the previous call's time (for off_path_s)
  int looks = 0;                // looks started
  std::vector<std::pair<int, double>> looked;  // track id, when its look began
};

/// The PTZ pan (rad, robot frame, 0 = ahead) to ask at `now_s`. `lens` the
/// PTZ lens in the robot frame; `ptz_half_fov_rad` its half field of view;
/// `recall` its detector's recall by distance (a track where it is 0 is not
/// worth a look). Call every tick (or every picture); `st` carries the look.
double activeLookPan(ActiveLookState& st, const ActiveLookParams& p, const std::vector<HumanTrack>& tracks,
                     const control::Pose2& pose, double lens_x_m, double lens_y_m, double ptz_half_fov_rad,
                     const RecallTable& recall, double now_s);

/// True while the head is turning toward or from a look (its pictures then are blurred: not taken).
inline bool activeLookTurning(const ActiveLookState& st, double now_s) { return now_s < st.settled_s; }

}  // namespace inspect::behavior
