#include "shared/navigation/obstacle_memory.hpp"

#include <algorithm>
#include <cmath>

#include "shared/serial/messages.hpp"

namespace inspect::navigation {

SonarRanges rangesFromMm(const std::array<uint16_t, kSonarCount>& range_mm) {
  SonarRanges out{};
  for (std::size_t i = 0; i < kSonarCount; ++i)
    out[i] = range_mm[i] == serial::kNoEcho ? std::numeric_limits<double>::quiet_NaN() : range_mm[i] / 1000.0;
  return out;
}

std::optional<Vec2> sonarPoint(const config::UltrasonicMount& mount, const config::UltrasonicConfig& sonar,
                               double range_m, double max_use_m, std::optional<double> wall_normal_rad) {
  if (!std::isfinite(range_m) || range_m < sonar.min_range_m || range_m > sonar.max_range_m || range_m > max_use_m)
    return std::nullopt;
  // The echo comes from the nearest surface point anywhere in the cone. With
  // no knowledge the axis is the best single guess; for a flat wall of known
  // normal it is the ray closest to that normal.
  double ray_rad = mount.yaw_rad;
  if (wall_normal_rad && std::isfinite(*wall_normal_rad)) {
    const double half = sonar.beam_width_rad / 2.0;
    ray_rad += std::clamp(control::wrapAngle(*wall_normal_rad - mount.yaw_rad), -half, half);
  }
  return Vec2{mount.x_m + range_m * std::cos(ray_rad), mount.y_m + range_m * std::sin(ray_rad)};
}

Vec2 toOdometryFrame(const control::Pose2& pose, Vec2 robot_point) {
  return Vec2{pose.x_m, pose.y_m} + rotated(robot_point, pose.theta_rad);
}

void ObstacleMemory::expire(double now_s, double max_age_s) {
  while (count_ > 0 && now_s - buf_[tail_].t_s > max_age_s) {
    tail_ = (tail_ + 1) % kCapacity;
    --count_;
  }
}

void ObstacleMemory::add(Vec2 point, double t_s) {
  if (!isFinite(point) || !std::isfinite(t_s)) return;
  if (count_ == kCapacity) {  // full: overwrite the oldest
    tail_ = (tail_ + 1) % kCapacity;
    --count_;
  }
  buf_[(tail_ + count_) % kCapacity] = {point, t_s};
  ++count_;
}

void ObstacleMemory::clear() {
  tail_ = 0;
  count_ = 0;
}

namespace {

// A side's points: weighted sums for the mean direction and for a
// least-squares line (weighted principal axis), then the segment's extent.
// Points enter relative to the robot, so that the sums of squares keep their
// precision far from the odometry origin.
struct SideSum {
  Vec2 push;                     // sum of w * unit(x - p)
  double weight = 0.0;
  double sw = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0, syy = 0.0;  // line fit (closeness only)
  Vec2 nearest_point;
  // Set by fitLine():
  Vec2 centre, dir;
  bool line = false;
  double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();

  void add(double w_recent, double w_fit, Vec2 unit_away, Vec2 p /* relative to the robot */) {
    push = push + w_recent * unit_away;
    weight += w_recent;
    sw += w_fit;
    sx += w_fit * p.x;
    sy += w_fit * p.y;
    sxx += w_fit * p.x * p.x;
    sxy += w_fit * p.x * p.y;
    syy += w_fit * p.y * p.y;
  }
  void fitLine() {
    if (sw <= 0.0) return;
    centre = {sx / sw, sy / sw};
    const double cxx = sxx / sw - centre.x * centre.x;
    const double cxy = sxy / sw - centre.x * centre.y;
    const double cyy = syy / sw - centre.y * centre.y;
    // Eigenvalues of the 2x2 covariance; the larger one's axis is the line.
    const double mean = (cxx + cyy) / 2.0;
    const double dev = std::sqrt(std::max(0.0, (cxx - cyy) * (cxx - cyy) / 4.0 + cxy * cxy));
    const double l1 = mean + dev;
    const double l2 = mean - dev;
    dir = geometry::unitAt(0.5 * std::atan2(2.0 * cxy, cxx - cyy));
    line = l1 > kMinAlong_m * kMinAlong_m && l2 < kMaxAcross_m * kMaxAcross_m && l2 < kMaxFlatness * l1;
  }
  void extend(Vec2 p /* relative to the robot */) {
    const double t = dot(p - centre, dir);
    lo = std::min(lo, t);
    hi = std::max(hi, t);
  }
  void finish(SideView& v, Vec2 x, Vec2 heading, double lookahead_m) const {
    if (std::isfinite(v.nearest_m)) v.away_from_nearest = normalized(x - nearest_point);
    const Vec2 robot{};  // the robot in the relative frame of the sums
    if (weight <= 0.0) return;
    Vec2 away;
    if (line && lo <= hi) {
      // x_o: the nearest point of the fitted segment (its end when the robot
      // has passed it, so that a convex corner is rounded).
      // The end ahead is extended: a side sonar yawed toward the wall sees it
      // only behind the robot, which must not look like the end of the wall.
      const bool ahead_is_hi = dot(heading, dir) >= 0.0;
      const double end_lo = ahead_is_hi ? lo : lo - lookahead_m;
      const double end_hi = ahead_is_hi ? hi + lookahead_m : hi;
      const Vec2 xo = centre + std::clamp(dot(robot - centre, dir), end_lo, end_hi) * dir;
      away = robot - xo;
      v.line_fit = norm(away) > 1e-6;
    }
    if (v.line_fit) {
      v.distance_m = norm(away);
      v.avoid = normalized(away);
    } else {
      v.avoid = normalized(push);
      v.distance_m = v.nearest_m;
    }
  }

  // A line: spread along it (standard deviation) over 0.03 m (some 0.1 m of
  // wall; the many points average the +-0.03 m sonar noise), across it within
  // sonar noise and smaller than along it.
  static constexpr double kMinAlong_m = 0.03;
  static constexpr double kMaxAcross_m = 0.05;
  static constexpr double kMaxFlatness = 0.45;  // variance ratio across / along (std ratio 2/3)
};

struct PointView {
  double d;
  bool on_right;
  bool on_left;
};

PointView viewOf(Vec2 p, Vec2 x, double theta_rad, double sector_rad) {
  const double bearing = control::wrapAngle(angleOf(p - x) - theta_rad);
  return {norm(x - p), bearing <= sector_rad, bearing >= -sector_rad};
}

}  // namespace

ObstacleSummary summarise(const ObstacleMemory& memory, const control::Pose2& pose, Vec2 goal, double now_s,
                          const NavigationParams& params) {
  ObstacleSummary s;
  const Vec2 x{pose.x_m, pose.y_m};
  const Vec2 to_goal = normalized(goal - x);
  const double goal_m = norm(goal - x);
  // The corridor ends at the goal: the robot stops there, so what lies beyond
  // (the wall behind a goal placed near it) is not in its way.
  const double corridor_m = std::min(params.guard_distance_m, goal_m);
  s.goal_near = goal_m <= params.guard_distance_m;
  const double dc = params.caution_distance_m;
  const double fc = params.follow_caution_m;
  Vec2 sum;
  double weight_sum = 0.0;
  SideSum right, left;
  for (std::size_t i = 0; i < memory.size(); ++i) {
    const auto& m = memory.at(i);
    const Vec2 p = m.p;
    const PointView v = viewOf(p, x, pose.theta_rad, params.follow_front_sector_rad);
    const double d = v.d;
    s.any = true;
    if (d < s.nearest_m) {
      s.nearest_m = d;
      s.nearest_point = p;
    }
    if (v.on_right && d < s.right.nearest_m) {
      s.right.nearest_m = d;
      right.nearest_point = p;
    }
    if (v.on_left && d < s.left.nearest_m) {
      s.left.nearest_m = d;
      left.nearest_point = p;
    }
    if (d <= 1e-9) continue;
    const Vec2 unit_away = (1.0 / d) * (x - p);
    // Fresh points count most in the avoid vector: the trail of older points
    // behind the robot would tilt it forward.
    const double recency = params.recency_s > 0.0 ? std::exp(-(now_s - m.t_s) / params.recency_s) : 1.0;
    if (d < dc) {
      // Eq 5.20 (u_AO = K (x - x_o)) for many points: each pushes along its
      // unit direction, weighted by closeness squared and recency.
      const double w = recency * ((dc - d) / dc) * ((dc - d) / dc);
      sum = sum + w * unit_away;
      weight_sum += w;
      ++s.points_in_caution;
    }
    if (d < fc) {
      // The followed boundary: only the points near enough to be it, so that
      // the far edge of a gap (or a sonar echo from it) does not bend the path.
      const double closeness = ((fc - d) / fc) * ((fc - d) / fc);
      if (v.on_right) right.add(recency * closeness, closeness, unit_away, p - x);
      if (v.on_left) left.add(recency * closeness, closeness, unit_away, p - x);
    }
    // Corridor toward the goal: a point ahead along the goal direction,
    // within the guard distance, short of the goal and closer to that line
    // than the half width.
    const Vec2 rel = p - x;
    const double along = dot(rel, to_goal);
    if (along > 0.0 && along < corridor_m &&
        std::abs(cross(to_goal, rel)) < params.clear_shot_half_width_m)
      s.goal_blocked = true;
  }
  if (weight_sum > 0.0) s.avoid = (1.0 / weight_sum) * sum;
  right.fitLine();
  left.fitLine();
  if (right.line || left.line) {
    for (std::size_t i = 0; i < memory.size(); ++i) {
      const Vec2 p = memory.point(i);
      const PointView v = viewOf(p, x, pose.theta_rad, params.follow_front_sector_rad);
      if (v.d >= fc) continue;
      if (right.line && v.on_right) right.extend(p - x);
      if (left.line && v.on_left) left.extend(p - x);
    }
  }
  const Vec2 heading = geometry::unitAt(pose.theta_rad);
  right.finish(s.right, x, heading, params.follow_lookahead_m);
  left.finish(s.left, x, heading, params.follow_lookahead_m);
  if (s.any) {
    s.away_from_nearest = normalized(x - s.nearest_point);
    s.nearest_bearing_rad = control::wrapAngle(angleOf(s.nearest_point - x) - pose.theta_rad);
  }
  return s;
}

}  // namespace inspect::navigation
