#pragma once
// Guard conditions of the navigation hybrid automaton (chapter 5.4.3): which
// side to follow a boundary on, when there is a clear shot at the goal, when
// progress has been made. Pure functions.
#include "shared/navigation/behaviours.hpp"
#include "shared/navigation/mode.hpp"
#include "shared/navigation/obstacle_memory.hpp"
#include "shared/geometry/vec2.hpp"

namespace inspect::navigation {

using geometry::Vec2;

/// Eq 5.24: the side whose boundary direction (Eq 5.23) makes an acute angle with the
/// goal direction, dot(u_FW, u_GTG) > 0. When the goal lies straight behind the obstacle
/// (both dot products ~0) the side closer to the current heading wins, then counter-clockwise.
FollowSide chooseSide(Vec2 avoid, Vec2 to_goal, Vec2 heading);

/// Eq 5.27: clear shot at the goal - the avoid and go-to-goal directions make an acute
/// angle, dot(u_AO, u_GTG) > 0, and no remembered point lies in the corridor toward the
/// goal within the guard distance. True when no obstacle is within the caution distance,
/// and when the goal itself lies within the guard distance with its corridor free.
bool clearShot(const ObstacleSummary& obs, Vec2 to_goal);

/// Eq 5.25: progress since the boundary was entered, |x - x_g| < d_tau - margin.
inline bool progressMade(double distance_to_goal_m, double d_tau_m, double margin_m) {
  return distance_to_goal_m < d_tau_m - margin_m;
}

}  // namespace inspect::navigation
