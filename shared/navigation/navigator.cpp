#include "shared/navigation/navigator.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

namespace inspect::navigation {

namespace {
// A sensor whose axis is within this of a followed wall's normal faces that wall.
constexpr double kWallFacingRad = 1.0;
}  // namespace

Navigator::Navigator(const NavigationParams& params, const config::UltrasonicConfig& sonar)
    : params_(params), sonar_(sonar) {
  if (const std::string err = checkParams(params); !err.empty())
    throw std::invalid_argument("navigation: " + err);
  heading_gains_ = {params.heading_kp, params.heading_ki, params.heading_kd};
  heading_cfg_.output_min = -params.w_max_rad_s;
  heading_cfg_.output_max = params.w_max_rad_s;
  heading_cfg_.integral_limit = params.w_max_rad_s;
  heading_cfg_.derivative_filter_s = 0.05;
}

void Navigator::resetCounters() {
  out_.switch_count = 0;
  out_.rapid_switch_count = 0;
  last_switch_s_ = -std::numeric_limits<double>::infinity();
}

void Navigator::setGoal(Vec2 goal) {
  if (!isFinite(goal)) {
    clearGoal();
    return;
  }
  goal_ = goal;
  has_goal_ = true;
  mode_ = Mode::kGoToGoal;
  mode_since_s_ = time_s_;
  side_ = FollowSide::kNone;
  d_tau_m_ = std::numeric_limits<double>::infinity();
  heading_pid_ = {};
  has_boundary_point_ = false;
  resetCounters();
}

void Navigator::clearGoal() {
  has_goal_ = false;
  mode_ = Mode::kAtGoal;
  mode_since_s_ = time_s_;
}

void Navigator::reset() {
  clearGoal();
  memory_.clear();
  obs_ = {};
  side_ = FollowSide::kNone;
  d_tau_m_ = std::numeric_limits<double>::infinity();
  heading_pid_ = {};
  has_boundary_point_ = false;
  resetCounters();
  out_ = {};
}

ObstacleSummary Navigator::boundaryView(const control::Pose2& pose) {
  ObstacleSummary o = obs_;
  SideView& v = side_ == FollowSide::kClockwise ? o.right : o.left;
  const Vec2 x{pose.x_m, pose.y_m};
  if (norm(v.avoid) > 0.0) {
    boundary_point_ = x - v.distance_m * v.avoid;  // x_o of Eq 5.20
    has_boundary_point_ = true;
  } else if (has_boundary_point_ && norm(x - boundary_point_) < v.nearest_m) {
    // Rounding the end of a thin wall, the end falls into the blind sector
    // behind the side sonar and leaves the memory after memory_s, long before
    // the half turn round it is done; without it the robot curved off toward
    // whatever else it remembered. The last x_o stays the boundary until the
    // sonars see one again.
    v.avoid = normalized(x - boundary_point_);
    v.distance_m = norm(x - boundary_point_);
  }
  return o;
}

void Navigator::switchTo(Mode m) {
  if (m == mode_) return;
  // Hybrid-automaton bookkeeping: count every switch and the rapid ones (chattering).
  ++out_.switch_count;
  if (time_s_ - last_switch_s_ < params_.chatter_window_s) ++out_.rapid_switch_count;
  last_switch_s_ = time_s_;
  mode_ = m;
  mode_since_s_ = time_s_;
  out_.switched = true;
  heading_pid_ = {};  // a new behaviour starts without the old one's integral or derivative
  has_boundary_point_ = false;
}

void Navigator::enterBoundary(const control::Pose2& pose, double distance_to_goal_m, Vec2 to_goal) {
  const Vec2 away = norm(obs_.avoid) > 0.0 ? obs_.avoid : obs_.away_from_nearest;
  side_ = chooseSide(away, to_goal, geometry::unitAt(pose.theta_rad));  // Eq 5.24
  d_tau_m_ = distance_to_goal_m;                              // reset: d_tau = |x - x_g| (Eq 5.25)
}

Mode Navigator::nextMode(const control::Pose2& pose, double distance_to_goal_m, Vec2 to_goal) {
  const NavigationParams& p = params_;
  if (mode_ == Mode::kAtGoal)
    return distance_to_goal_m > p.goal_epsilon_m + p.goal_release_m ? Mode::kGoToGoal : Mode::kAtGoal;
  if (distance_to_goal_m < p.goal_epsilon_m) return Mode::kAtGoal;
  // Safety overrides the dwell time: too close is handled at once.
  if (obs_.nearest_m < p.safety_distance_m && mode_ != Mode::kAvoid) {
    if (mode_ == Mode::kGoToGoal) enterBoundary(pose, distance_to_goal_m, to_goal);
    return Mode::kAvoid;
  }
  if (time_s_ - mode_since_s_ < p.min_dwell_s) return mode_;
  switch (mode_) {
    case Mode::kGoToGoal:
      // Obstacle within the guard distance and in the way of the goal.
      if (obs_.nearest_m < p.guard_distance_m && !out_.clear_shot) {
        enterBoundary(pose, distance_to_goal_m, to_goal);
        return followMode(side_);
      }
      return mode_;
    case Mode::kFollowCw:
    case Mode::kFollowCcw:
      return out_.clear_shot && out_.progress ? Mode::kGoToGoal : mode_;  // Eqs 5.25 AND 5.27
    case Mode::kAvoid:
      return obs_.nearest_m > p.safety_distance_m + p.distance_hysteresis_m ? followMode(side_) : mode_;
    case Mode::kAtGoal: break;
  }
  return mode_;
}

control::Twist Navigator::command(const control::Pose2& pose, double dt_s) {
  Steer s;
  switch (mode_) {
    case Mode::kAtGoal: return stop();
    case Mode::kGoToGoal:
      if (params_.style == SwitchingStyle::kBlend) {
        out_.blend_weight = norm(obs_.avoid) > 0.0 ? blendWeight(obs_.nearest_m, params_) : 0.0;
        s = blendSteer(pose, goal_, obs_, params_);
      } else {
        s = goToGoalSteer(pose, goal_, params_);
      }
      break;
    case Mode::kAvoid: s = avoidSteer(pose, obs_, params_); break;
    case Mode::kFollowCw:
    case Mode::kFollowCcw: s = followSteer(pose, boundaryView(pose), side_, params_); break;
  }
  // Eq 5.13 on the heading error (Eq 5.14). The PID is fed setpoint 0 and
  // measurement -e so that its derivative acts on the wrapped error, never
  // on a raw angle that jumps by 2 pi.
  const double e = control::wrapAngle(s.heading_rad - pose.theta_rad);
  const double w = control::pidStep(heading_cfg_, heading_gains_, heading_pid_, 0.0, -e, dt_s);
  return limitTwist({s.speed_m_s * std::max(0.0, std::cos(e)), w}, params_);
}

const NavigationOutput& Navigator::step(const control::Pose2& pose, const SonarRanges& ranges_m, double dt_s) {
  out_.switched = false;
  if (!std::isfinite(pose.x_m) || !std::isfinite(pose.y_m) || !std::isfinite(pose.theta_rad) ||
      !std::isfinite(dt_s) || dt_s <= 0.0) {
    out_.twist = stop();
    return out_;
  }
  time_s_ += dt_s;
  memory_.expire(time_s_, params_.memory_s);
  // While following a boundary, a sensor facing it sees that boundary; a flat
  // wall echoes from the ray of the cone closest to its normal, so the point
  // goes there and not on the axis (on the axis the points slide along the
  // wall as the robot yaws, and the wall seems to turn with the robot).
  std::optional<double> normal_rad;
  if (mode_ == Mode::kFollowCw || mode_ == Mode::kFollowCcw) {
    const SideView& v = side_ == FollowSide::kClockwise ? obs_.right : obs_.left;
    if (norm(v.avoid) > 0.0) normal_rad = control::wrapAngle(angleOf(-1.0 * v.avoid) - pose.theta_rad);
  }
  for (std::size_t i = 0; i < kSonarCount; ++i) {
    const auto& mount = sonar_.mounts[i];
    std::optional<double> hint;
    if (normal_rad && std::abs(control::wrapAngle(*normal_rad - mount.yaw_rad)) < kWallFacingRad) hint = normal_rad;
    if (const auto pt = sonarPoint(mount, sonar_, ranges_m[i], params_.perception_range_m, hint))
      memory_.add(toOdometryFrame(pose, *pt), time_s_);
  }

  const Vec2 x{pose.x_m, pose.y_m};
  const Vec2 goal = has_goal_ ? goal_ : x;
  obs_ = summarise(memory_, pose, goal, time_s_, params_);
  const double dist = norm(goal - x);
  const Vec2 to_goal = normalized(goal - x);
  out_.distance_to_goal_m = dist;
  out_.nearest_obstacle_m = obs_.nearest_m;
  out_.nearest_bearing_rad = obs_.nearest_bearing_rad;
  out_.clear_shot = clearShot(obs_, to_goal);
  out_.progress = progressMade(dist, d_tau_m_, params_.progress_margin_m);
  out_.blend_weight = 0.0;

  if (has_goal_) switchTo(nextMode(pose, dist, to_goal));
  out_.mode = mode_;
  out_.side = side_;
  out_.progress_reference_m = d_tau_m_;
  out_.time_in_mode_s = time_s_ - mode_since_s_;
  out_.twist = command(pose, dt_s);
  return out_;
}

}  // namespace inspect::navigation
