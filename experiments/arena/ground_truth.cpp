#include "experiments/arena/ground_truth.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "shared/world/world.hpp"

namespace inspect::arena {

namespace {
constexpr double kDeg = std::numbers::pi / 180.0;
}  // namespace

behavior::Pattern truePattern(const control::Pose2& robot, const TruePerson& p, const TruthParams& t) {
  using behavior::Pattern;
  const double speed = std::hypot(p.velocity.x, p.velocity.y);
  if (speed < t.min_speed_m_s) return Pattern::kNone;
  // The person in the robot's frame: x ahead, y to the left.
  const double dx = p.position.x - robot.x_m, dy = p.position.y - robot.y_m;
  const double c = std::cos(robot.theta_rad), s = std::sin(robot.theta_rad);
  const double ahead = c * dx + s * dy, lateral = -s * dx + c * dy;
  if (ahead <= 0.0 || std::hypot(ahead, lateral) > t.max_range_m) return Pattern::kNone;
  const double phi = std::fabs(control::wrapAngle(std::atan2(p.velocity.y, p.velocity.x) - robot.theta_rad)) / kDeg;
  if (phi > t.crossing_min_deg && phi < t.crossing_max_deg) return Pattern::kCrossing;
  const double side = std::fabs(lateral);
  if (side > t.max_lateral_m) return Pattern::kNone;
  const bool on_path = side <= t.path_half_width_m;
  if (phi <= t.crossing_min_deg) return on_path ? Pattern::kLeading : Pattern::kNone;
  return on_path ? Pattern::kConfronting : Pattern::kEncountering;
}

bool observable(const control::Pose2& robot, const TruePerson& p, const config::UltrasonicConfig& sonar,
                const world::World& w) {
  for (const auto& m : sonar.mounts) {
    const control::Pose2 at = config::mountPose(robot, m);
    const double dx = p.position.x - at.x_m, dy = p.position.y - at.y_m;
    const double d = std::hypot(dx, dy);
    const double near = std::max(0.0, d - p.radius_m);
    if (near > sonar.max_range_m) continue;
    // The disc reaches into the cone when its centre's bearing is within the
    // half beam plus the half angle the disc subtends.
    const double bearing = std::fabs(control::wrapAngle(std::atan2(dy, dx) - at.theta_rad));
    const double subtends = d > p.radius_m ? std::asin(p.radius_m / d) : std::numbers::pi;
    if (bearing > sonar.beam_width_rad / 2 + subtends) continue;
    // Nothing solid in between (along the line to the centre, up to the disc's near side).
    const auto hit = world::castRay(w, {at.x_m, at.y_m}, std::atan2(dy, dx), near);
    if (!hit || *hit >= near) return true;
  }
  return false;
}

}  // namespace inspect::arena
