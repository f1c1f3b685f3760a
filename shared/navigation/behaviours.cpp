#include "shared/navigation/behaviours.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace inspect::navigation {

namespace {

// Direction away from the obstacles: the avoid vector, or (when every point
// is beyond the caution distance) the direction from the nearest point.
Vec2 awayDirection(const ObstacleSummary& obs) {
  const Vec2 a = normalized(obs.avoid);
  return norm(a) > 0.0 ? a : obs.away_from_nearest;
}

}  // namespace

Steer goToGoalSteer(const control::Pose2& pose, Vec2 goal, const NavigationParams& p) {
  const Vec2 e = goal - Vec2{pose.x_m, pose.y_m};
  // Eq 5.14: theta_d = atan2(y_g - y, x_g - x); Eq 5.19: v = K |x_g - x| (capped).
  return {angleOf(e), std::min(p.speed_kp * norm(e), p.v_max_m_s)};
}

Steer avoidSteer(const control::Pose2& pose, const ObstacleSummary& obs, const NavigationParams& p) {
  const Vec2 a = awayDirection(obs);
  if (norm(a) == 0.0) return {pose.theta_rad, 0.0};  // nothing to avoid: hold still
  return {angleOf(a), p.avoid_speed_m_s};
}

Vec2 followDirection(Vec2 avoid, FollowSide side) {
  const Vec2 a = normalized(avoid);
  switch (side) {
    case FollowSide::kClockwise: return rotated(a, -std::numbers::pi / 2.0);       // Eq 5.23, u_FW_c
    case FollowSide::kCounterClockwise: return rotated(a, std::numbers::pi / 2.0);  // Eq 5.23, u_FW_cc
    case FollowSide::kNone: break;
  }
  return {};
}

Steer followSteer(const control::Pose2& pose, const ObstacleSummary& obs, FollowSide side,
                  const NavigationParams& p) {
  // The boundary on the follow side (and ahead), not what lies across a gap.
  const SideView& view = side == FollowSide::kClockwise ? obs.right : obs.left;
  const Vec2 va = normalized(view.avoid);
  const Vec2 a = norm(va) > 0.0 ? va : view.away_from_nearest;
  if (norm(a) == 0.0 || side == FollowSide::kNone) {
    // Boundary lost: curve toward the side it was on (left for ccw).
    const double turn = side == FollowSide::kClockwise ? -p.search_turn_rad : p.search_turn_rad;
    return {control::wrapAngle(pose.theta_rad + turn), p.follow_speed_m_s};
  }
  // Distance keeping: too far -> lean toward the boundary (-a), too close -> away.
  const double c = std::clamp(p.follow_gain_1_m * (view.distance_m - p.follow_distance_m), -p.follow_correction_max,
                              p.follow_correction_max);
  const Vec2 dir = followDirection(a, side) - c * a;
  return {angleOf(dir), p.follow_speed_m_s};
}

double blendWeight(double nearest_m, const NavigationParams& p) {
  if (!(nearest_m < p.caution_distance_m)) return 0.0;
  const double s = std::clamp((p.caution_distance_m - nearest_m) / (p.caution_distance_m - p.guard_distance_m), 0.0,
                              1.0);
  return p.blend_max_weight * s * s * (3.0 - 2.0 * s);  // smoothstep: no kink at either end
}

Steer blendSteer(const control::Pose2& pose, Vec2 goal, const ObstacleSummary& obs, const NavigationParams& p) {
  const Steer gtg = goToGoalSteer(pose, goal, p);
  const double w = blendWeight(obs.nearest_m, p);
  const Vec2 a = normalized(obs.avoid);
  if (w <= 0.0 || norm(a) == 0.0) return gtg;
  // Eq 5.21 with unit vectors; w < 0.5 keeps the sum pointing goal-ward when
  // the two are opposite, so the blend itself never stalls the robot.
  const Vec2 u = (1.0 - w) * geometry::unitAt(gtg.heading_rad) + w * a;
  return {angleOf(u), gtg.speed_m_s};
}

control::Twist limitTwist(control::Twist t, const NavigationParams& p) {
  const double v = std::isfinite(t.v_m_s) ? std::clamp(t.v_m_s, 0.0, p.v_max_m_s) : 0.0;
  const double w = std::isfinite(t.w_rad_s) ? std::clamp(t.w_rad_s, -p.w_max_rad_s, p.w_max_rad_s) : 0.0;
  return {v, w};
}

control::Twist steerTwist(const control::Pose2& pose, const Steer& s, const NavigationParams& p) {
  const double e = control::wrapAngle(s.heading_rad - pose.theta_rad);  // Eq 5.14
  return limitTwist({s.speed_m_s * std::max(0.0, std::cos(e)), p.heading_kp * e}, p);  // Eq 5.15 (P)
}

control::Twist goToGoal(const control::Pose2& pose, Vec2 goal, const NavigationParams& p) {
  return steerTwist(pose, goToGoalSteer(pose, goal, p), p);
}

control::Twist avoidObstacle(const control::Pose2& pose, const ObstacleSummary& obs, const NavigationParams& p) {
  return steerTwist(pose, avoidSteer(pose, obs, p), p);
}

control::Twist followBoundary(const control::Pose2& pose, const ObstacleSummary& obs, FollowSide side,
                              const NavigationParams& p) {
  return steerTwist(pose, followSteer(pose, obs, side, p), p);
}

control::Twist blended(const control::Pose2& pose, Vec2 goal, const ObstacleSummary& obs,
                       const NavigationParams& p) {
  return steerTwist(pose, blendSteer(pose, goal, obs, p), p);
}

}  // namespace inspect::navigation
