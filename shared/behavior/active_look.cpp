#include "shared/behavior/active_look.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace inspect::behavior {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

struct FromLens {
  double bearing_rad = 0, dist_m = 0;
};

// A track's bearing and distance from the PTZ lens, in the robot frame.
FromLens fromLens(const HumanTrack& t, const control::Pose2& pose, double lens_x, double lens_y) {
  const double dx = t.x[0] - pose.x_m, dy = t.x[1] - pose.y_m;
  const double c = std::cos(pose.theta_rad), s = std::sin(pose.theta_rad);
  const double fx = c * dx + s * dy - lens_x, fy = -s * dx + c * dy - lens_y;
  return {std::atan2(fy, fx), std::hypot(fx, fy)};
}

// Sonar-only so far: no head has found it, and the camera has not ruled it out.
bool undecided(const HumanTrack& t) { return t.confirmed && t.camera_hits == 0 && !t.camera_denied && !t.camera_doubted; }

// Turning from the pan asked now to `to`: when the head is there.
void turnTo(ActiveLookState& st, const ActiveLookParams& p, double to, double now_s) {
  st.settled_s = now_s + std::abs(to - st.pan_rad) / (p.slew_deg_s * kDeg);
  st.pan_rad = to;
}

}  // namespace

double activeLookPan(ActiveLookState& st, const ActiveLookParams& p, const std::vector<HumanTrack>& tracks,
                     const control::Pose2& pose, double lens_x_m, double lens_y_m, double ptz_half_fov_rad,
                     const RecallTable& recall, double now_s) {
  if (st.last_s >= 0 && now_s > st.last_s && std::abs(st.pan_rad) > ptz_half_fov_rad)
    st.off_path_s += now_s - st.last_s;
  st.last_s = now_s;
  const double max_pan = p.max_pan_deg * kDeg;
  // Someone ahead: the head belongs on the path.
  bool ahead = false;
  for (const auto& t : tracks) {
    if (!t.isPerson()) continue;
    const FromLens f = fromLens(t, pose, lens_x_m, lens_y_m);
    ahead = ahead || (f.dist_m <= p.ahead_m && std::abs(f.bearing_rad) <= p.ahead_deg * kDeg);
  }
  std::erase_if(st.looked, [&](const auto& l) { return now_s - l.second > p.revisit_s; });

  if (st.target_id >= 0) {
    const auto it = std::find_if(tracks.begin(), tracks.end(), [&](const HumanTrack& t) { return t.id == st.target_id; });
    const bool over = !p.enabled || ahead || it == tracks.end() || !undecided(*it) || now_s >= st.until_s;
    if (over) {
      st.target_id = -1;
      turnTo(st, p, 0.0, now_s);
      return st.pan_rad;
    }
    // Follow the track while looking (it may walk; the robot drives).
    const FromLens f = fromLens(*it, pose, lens_x_m, lens_y_m);
    st.pan_rad = std::clamp(f.bearing_rad, -max_pan, max_pan);
    return st.pan_rad;
  }
  if (!p.enabled || ahead || now_s < st.settled_s) return st.pan_rad;

  // The nearest undecided track out of the wide head's view, in the PTZ head's reach.
  const HumanTrack* best = nullptr;
  double best_dist = 1e18, best_bearing = 0;
  for (const auto& t : tracks) {
    if (!undecided(t)) continue;
    if (std::any_of(st.looked.begin(), st.looked.end(), [&](const auto& l) { return l.first == t.id; })) continue;
    const FromLens f = fromLens(t, pose, lens_x_m, lens_y_m);
    if (std::abs(f.bearing_rad) < p.min_off_axis_deg * kDeg || std::abs(f.bearing_rad) > max_pan + ptz_half_fov_rad)
      continue;
    if (!(recall.at(f.dist_m) > 0)) continue;
    if (f.dist_m < best_dist) {
      best = &t;
      best_dist = f.dist_m;
      best_bearing = f.bearing_rad;
    }
  }
  if (!best) return st.pan_rad;
  st.target_id = best->id;
  turnTo(st, p, std::clamp(best_bearing, -max_pan, max_pan), now_s);
  st.until_s = st.settled_s + p.dwell_s;
  st.looked.emplace_back(best->id, now_s);
  ++st.looks;
  return st.pan_rad;
}

}  // namespace inspect::behavior
