#pragma once
// The navigation behaviours of the chapter (5.3-5.4) as pure functions of the
// pose, the goal, the obstacle summary and the parameters. Each behaviour
// first chooses a direction of travel and a speed (a Steer, the chapter's
// velocity vector u of the point-mass model); steerTwist() turns that into a
// unicycle twist (Section 5.4.4): heading error through atan2 wrapped to
// [-pi, pi] (Eq 5.14), w = kp * error (Eq 5.15, P part), forward speed shaped by
// cos(error) so the robot turns on the spot instead of driving off course.
#include "shared/control/diff_drive.hpp"
#include "shared/navigation/mode.hpp"
#include "shared/navigation/navigation_params.hpp"
#include "shared/navigation/obstacle_memory.hpp"
#include "shared/geometry/vec2.hpp"

namespace inspect::navigation {

using geometry::Vec2;

/// A behaviour's request: direction of travel (odometry frame) and speed before shaping.
struct Steer {
  double heading_rad = 0.0;
  double speed_m_s = 0.0;
};

/// Go-to-goal (Eqs 5.14, 5.19): toward the goal at speed_kp * distance, capped at v_max_m_s.
Steer goToGoalSteer(const control::Pose2& pose, Vec2 goal, const NavigationParams& p);
/// Avoid-obstacle (Eq 5.20): along the avoid vector, away from the obstacles, at avoid_speed_m_s.
Steer avoidSteer(const control::Pose2& pose, const ObstacleSummary& obs, const NavigationParams& p);
/// Eq 5.23: the boundary direction, unit u_AO rotated by -pi/2 (clockwise) or +pi/2 (counter-clockwise).
Vec2 followDirection(Vec2 avoid, FollowSide side);
/// Boundary following: followDirection plus a correction toward follow_distance_m; when no
/// obstacle is remembered, curves toward the side the boundary was on to find it again.
Steer followSteer(const control::Pose2& pose, const ObstacleSummary& obs, FollowSide side,
                  const NavigationParams& p);
/// Blending weight of the avoid behaviour (Eq 5.21's 1 - alpha): 0 beyond the caution distance,
/// rising smoothly to blend_max_weight at the guard distance and below.
double blendWeight(double nearest_m, const NavigationParams& p);
/// Blended action (Eq 5.21): (1 - w) u_GTG + w u_AO (unit vectors), go-to-goal speed.
Steer blendSteer(const control::Pose2& pose, Vec2 goal, const ObstacleSummary& obs, const NavigationParams& p);

/// Twist for a Steer: w = heading_kp * wrap(heading - theta), v = speed * max(0, cos(error)),
/// both limited to v_max_m_s / w_max_rad_s.
control::Twist steerTwist(const control::Pose2& pose, const Steer& s, const NavigationParams& p);
/// Clamps v to [0, v_max_m_s] and w to +-w_max_rad_s; non-finite values become 0.
control::Twist limitTwist(control::Twist t, const NavigationParams& p);

/// Go-to-goal behaviour as a twist.
control::Twist goToGoal(const control::Pose2& pose, Vec2 goal, const NavigationParams& p);
/// Avoid-obstacle behaviour as a twist.
control::Twist avoidObstacle(const control::Pose2& pose, const ObstacleSummary& obs, const NavigationParams& p);
/// Follow-boundary behaviour as a twist.
control::Twist followBoundary(const control::Pose2& pose, const ObstacleSummary& obs, FollowSide side,
                              const NavigationParams& p);
/// Blended go-to-goal + avoid as a twist.
control::Twist blended(const control::Pose2& pose, Vec2 goal, const ObstacleSummary& obs,
                       const NavigationParams& p);
/// Stop behaviour (AT_GOAL).
inline control::Twist stop() { return {}; }

}  // namespace inspect::navigation
