// The camera's measurements in the people tracker (human_tracker.hpp;
// docs/human-awareness.md, "Fusion").
//
// A detection is a bearing b from the lens and, with the feet in view, a
// range r along the floor. The filter takes it as a position in the
// odometry frame with the polar noise turned Cartesian (a converted
// measurement): z = l + r (cos b, sin b), R = J diag(sr^2, sb^2) J', J the
// Jacobian of (r, b) -> (x, y). A bearing alone (feet out of view) is the
// track's offset across the ray, and the update moves the track across the
// ray only, its range from the lens and the range's rate left as they were
// (the optimal gain moves them too, through the track's range-lateral
// correlation: in the test a person stepping sideways 0.5 m at 5 m was
// pulled 1.2 m closer, and then given 2 m/s toward the robot). Noise:
// the bearing's sigma from bench_people (p90 0.35 deg, plus the picture's
// age), the range's a fraction of the range (the foot row is coarse: p50 12 %).
//
// Association is the nearest track by the normalised innovation
// nu' S^-1 nu within a chi-square gate, each track at most once a picture;
// a detection with a range and no track starts one (a camera-only track).
//
// Person evidence: log-odds per track, + hit_logodds for a detection,
// + ln(1 - recall(d)) for a picture whose view held the track at distance d
// (not at its edge, not hidden behind a closer track) without finding it.
#include <algorithm>
#include <cmath>
#include <span>

#include "shared/behavior/human_tracker.hpp"

namespace inspect::behavior {
namespace {
double wrapAngle(double a) { return std::remainder(a, 2 * M_PI); }

/// Range and bearing of a track from the lens.
struct Polar {
  double bearing = 0, range = 0;
};
Polar polarFrom(const Eigen::Vector2d& lens, const HumanTrack& t) {
  const double dx = t.x[0] - lens.x(), dy = t.x[1] - lens.y();
  return {std::atan2(dy, dx), std::hypot(dx, dy)};
}

/// A detection as a position with its covariance (converted measurement).
struct Converted {
  Eigen::Vector2d z;
  Eigen::Matrix2d r;
};
Converted convert(const Eigen::Vector2d& lens, double bearing, double range, double sigma_range, double sigma_bearing) {
  const double c = std::cos(bearing), s = std::sin(bearing);
  Eigen::Matrix2d jac;
  jac << c, -range * s, s, range * c;
  return {lens + range * Eigen::Vector2d(c, s),
          jac * Eigen::Vector2d(sigma_range * sigma_range, sigma_bearing * sigma_bearing).asDiagonal() * jac.transpose()};
}
/// A bearing alone as a measurement of the track's offset across the ray
/// (the innovation nu, its variance s, the row h, the ray's direction).
struct BearingOnly {
  double nu = 0, s = 0, r = 0;
  Eigen::Matrix<double, 1, 4> h = Eigen::Matrix<double, 1, 4>::Zero();
  Eigen::Vector2d along;
};
BearingOnly bearingOnly(const Eigen::Vector2d& lens, double bearing, double sigma_bearing, const HumanTrack& t) {
  BearingOnly b;
  b.along = Eigen::Vector2d(std::cos(bearing), std::sin(bearing));
  const Eigen::Vector2d across(-b.along.y(), b.along.x());
  const Eigen::Vector2d rel = t.x.head<2>() - lens;
  b.h << across.x(), across.y(), 0, 0;
  b.nu = -across.dot(rel);  // the ray passes through the lens: the track's offset from it, negated
  const double range = std::max(0.3, b.along.dot(rel));
  b.r = range * range * sigma_bearing * sigma_bearing;
  b.s = (b.h * t.p * b.h.transpose())(0, 0) + b.r;
  return b;
}
}  // namespace

void HumanTracker::addPersonEvidence(HumanTrack& t, double logodds) {
  const auto& c = p_.camera;
  t.person_logodds = std::clamp(t.person_logodds + logodds, -c.max_logodds, c.max_logodds);
  const bool denied = t.person_logodds <= c.deny_logodds;
  if (denied && !t.camera_denied) ++counters_.camera_denials;
  t.camera_denied = denied;
  t.camera_doubted = t.camera_hits == 0 && t.person_logodds < 0 && t.person_logodds <= c.doubt_logodds;
}

void HumanTracker::countCameraMisses(const control::Pose2& pose, const CameraLook& look, const Eigen::Vector2d& lens,
                                     std::span<const bool> matched) {
  const CameraFusionParams& c = p_.camera;
  // Another track hides one when it is on the same bearing and at least a
  // body's depth closer (two tracks side by side, as the two front sonars make
  // of one wide object, do not hide each other).
  constexpr double kPersonDepth_m = 0.5;
  const double axis = pose.theta_rad + look.axis_rad;
  const double half = look.half_fov_rad - c.edge_margin_deg * M_PI / 180.0;
  for (std::size_t j = 0; j < matched.size(); ++j) {
    if (matched[j]) continue;
    HumanTrack& t = tracks_[j];
    const Polar pr = polarFrom(lens, t);
    const double recall = c.recallAt(pr.range, look.wide);
    if (recall <= 0.0 || std::abs(wrapAngle(pr.bearing - axis)) > half) continue;
    // Hidden behind a closer track on the same bearing?
    bool hidden = false;
    for (std::size_t o = 0; o < tracks_.size() && !hidden; ++o) {
      if (o == j) continue;
      const Polar po = polarFrom(lens, tracks_[o]);
      hidden = po.range + kPersonDepth_m < pr.range && std::abs(wrapAngle(po.bearing - pr.bearing)) < std::atan2(c.occluder_width_m, po.range);
    }
    if (hidden) continue;
    ++t.camera_misses;
    ++counters_.camera_misses;
    addPersonEvidence(t, std::log(1.0 - std::min(recall, 0.99)));
  }
}

void HumanTracker::observeCamera(const control::Pose2& pose, const CameraLook& look) {
  const CameraFusionParams& c = p_.camera;
  if (!c.enabled || !have_time_) return;
  const double t_s = last_t_s_;  // the tracks as of the last step (at most a tick old)
  ++counters_.camera_looks;
  const control::Pose2 lp = config::mountPose(pose, {look.lens_x_m, look.lens_y_m, 0.0});
  const Eigen::Vector2d lens(lp.x_m, lp.y_m);
  const double sb = c.bearing_sigma_deg * M_PI / 180.0;
  // Which tracks a detection of this picture went to (tracks_ holds at most
  // max_tracks; a track created here is never matched again in this picture).
  constexpr std::size_t kMaxMatched = 64;
  std::array<bool, kMaxMatched> matched{}, merged{};
  std::array<double, kMaxMatched> d2s{};
  const std::size_t before = std::min(tracks_.size(), kMaxMatched);
  for (std::size_t k = 0; k < look.count && k < look.people.size(); ++k) {
    const CameraPerson& seen = look.people[k];
    if (!std::isfinite(seen.bearing_rad) || !std::isfinite(seen.range_m)) continue;
    ++counters_.camera_detections;
    const bool ranged = seen.range_m > 0;
    // The foot row reads long by the detector's median (its boxes end above the soles).
    const double range = ranged ? seen.range_m / (1.0 + c.range_bias_frac) : 0.0;
    const double bearing = wrapAngle(pose.theta_rad + seen.bearing_rad);
    const double sr = std::max(0.05, c.range_sigma_frac * range);
    const Converted m = convert(lens, bearing, range, sr, sb);
    // 1. The nearest track by normalised innovation.
    std::size_t best = kMaxMatched;
    double best_d2 = c.gate_chi2;
    for (std::size_t j = 0; j < before; ++j) {
      d2s[j] = c.gate_chi2;
      if (matched[j]) continue;
      const HumanTrack& t = tracks_[j];
      if (polarFrom(lens, t).range < 0.3) continue;
      double& d2 = d2s[j];
      if (ranged) {
        const Eigen::Vector2d nu = m.z - t.x.head<2>();
        const Eigen::Matrix2d s = t.p.block<2, 2>(0, 0) + m.r;
        d2 = nu.dot(s.ldlt().solve(nu));
      } else {
        const BearingOnly b = bearingOnly(lens, bearing, sb, t);
        d2 = b.nu * b.nu / b.s;
      }
      if (d2 < best_d2) {
        best_d2 = d2;
        best = j;
      }
    }
    // 2. The Kalman update of that track.
    if (best < kMaxMatched) {
      HumanTrack& t = tracks_[best];
      if (ranged) {
        update(t, m.z, m.r, t_s);
      } else {
        // Across the ray only, and the range from the lens and its rate left
        // as they were: a bearing says nothing of the range, but the optimal
        // gain moves both through the track's range-lateral correlation (a
        // person stepping sideways would be taken for one walking closer).
        const BearingOnly b = bearingOnly(lens, bearing, sb, t);
        Eigen::Vector4d gain = t.p * b.h.transpose() / b.s;
        gain.head<2>() -= b.along * b.along.dot(gain.head<2>());
        gain.tail<2>() -= b.along * b.along.dot(gain.tail<2>());
        const Eigen::Matrix4d ikh = Eigen::Matrix4d::Identity() - gain * b.h;
        t.x += gain * b.nu;
        t.p = ikh * t.p * ikh.transpose() + gain * b.r * gain.transpose();  // Joseph form: the gain is not optimal
        t.last_seen_s = t_s;
        ++t.hits;
      }
      t.p = 0.5 * (t.p + t.p.transpose());
      ++t.camera_hits;
      t.camera_seen_s = t_s;
      t.camera_misses = 0;
      addPersonEvidence(t, c.hit_logodds);
      matched[best] = true;
      ++counters_.camera_associated;
      // Sonar-only tracks inside the same gate are this person too (a sonar
      // track starts where the camera's coarse range did not reach its echo):
      // each goes into this one as a measurement of its position (the
      // sonar's range is the better one), and goes.
      for (std::size_t j = 0; j < before; ++j) {
        if (matched[j] || d2s[j] >= c.gate_chi2 || tracks_[j].camera_hits > 0) continue;
        const HumanTrack& o = tracks_[j];
        update(t, o.x.head<2>(), o.p.block<2, 2>(0, 0), t_s);
        t.first_seen_s = std::min(t.first_seen_s, o.first_seen_s);
        t.person = t.person || o.person;
        t.confirmed = t.confirmed || o.confirmed;
        matched[j] = merged[j] = true;
        ++counters_.camera_merged;
      }
      continue;
    }
    // 3. A camera-only track, at the detection with its covariance.
    if (!ranged || range > c.max_new_range_m || static_cast<int>(tracks_.size()) >= p_.max_tracks) continue;
    HumanTrack t = newTrack(m.z, m.r, t_s);
    t.camera_hits = 1;
    t.camera_seen_s = t_s;
    addPersonEvidence(t, c.hit_logodds);
    tracks_.push_back(t);
    ++counters_.camera_tracks_created;
  }
  // 4. The tracks this picture should have shown and did not.
  countCameraMisses(pose, look, lens, std::span<const bool>(matched.data(), before));
  for (std::size_t j = before; j-- > 0;)
    if (merged[j]) tracks_.erase(tracks_.begin() + static_cast<std::ptrdiff_t>(j));
}

}  // namespace inspect::behavior
