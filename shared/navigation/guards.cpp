#include "shared/navigation/guards.hpp"

#include <cmath>

namespace inspect::navigation {

namespace {
// |dot| below this counts as "goal straight behind the obstacle".
constexpr double kSideTie = 1e-3;
}  // namespace

FollowSide chooseSide(Vec2 avoid, Vec2 to_goal, Vec2 heading) {
  const Vec2 cw = followDirection(avoid, FollowSide::kClockwise);
  const double to_goal_dot = dot(cw, normalized(to_goal));  // the ccw direction is -cw
  if (to_goal_dot > kSideTie) return FollowSide::kClockwise;
  if (to_goal_dot < -kSideTie) return FollowSide::kCounterClockwise;
  return dot(cw, normalized(heading)) > kSideTie ? FollowSide::kClockwise : FollowSide::kCounterClockwise;
}

bool clearShot(const ObstacleSummary& obs, Vec2 to_goal) {
  if (obs.goal_blocked) return false;
  // The corridor to a goal within the guard distance was checked end to end
  // and is free: nothing is in the way, whatever the obstacles around push.
  // (Without this a boundary entered near the goal, by a wall beside or
  // behind it, records d_tau below the progress margin and is never left.)
  if (obs.goal_near) return true;
  const Vec2 a = normalized(obs.avoid);
  if (norm(a) == 0.0) return true;  // nothing within the caution distance
  return dot(a, normalized(to_goal)) > 0.0;
}

}  // namespace inspect::navigation
