#include "shared/robot/route_runner.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "shared/util/number_text.hpp"

namespace inspect::robot {

using util::fmtFixed;
using util::fmtPoint;

std::string RouteRunner::plan(const v1::GoTo& g, const config::RobotConfig& robot, Plan& out) {
  if (g.points_size() == 0) return "no goal given";
  if (g.points_size() > kMaxGoals)
    return std::to_string(g.points_size()) + " goals: at most " + std::to_string(kMaxGoals) + " per command";
  for (int i = 0; i < g.points_size(); ++i) {
    const auto& p = g.points(i);
    if (!std::isfinite(p.x_m()) || !std::isfinite(p.y_m()))
      return "goal " + std::to_string(i + 1) + " has a non-finite coordinate";
    if (!std::isfinite(p.dwell_s()) || p.dwell_s() < 0.0 || p.dwell_s() > 3600.0)
      return "goal " + std::to_string(i + 1) + ": dwell_s must be within [0, 3600] s";
    if (p.has_ptz() && (!std::isfinite(p.ptz().pan_rad()) || !std::isfinite(p.ptz().tilt_rad()) ||
                        std::abs(p.ptz().pan_rad()) > M_PI || std::abs(p.ptz().tilt_rad()) > M_PI / 2))
      return "goal " + std::to_string(i + 1) + ": camera pan must be within [-pi, pi], tilt [-pi/2, pi/2]";
  }
  const double speed = g.speed_m_s();
  if (!std::isfinite(speed) || speed < 0.0) return "speed must be a number >= 0 m/s (0 = default)";
  if (speed > robot.limits.max_v_m_s)
    return "speed " + fmtFixed(speed) + " m/s is above the robot's limit of " + fmtFixed(robot.limits.max_v_m_s) +
           " m/s";
  navigation::NavigationParams params;
  params.v_max_m_s = std::min(speed > 0.0 ? speed : kDefaultSpeed_m_s, robot.limits.max_v_m_s);
  params.w_max_rad_s = std::min(params.w_max_rad_s, robot.limits.max_w_rad_s);
  try {
    out.navigator = std::make_unique<navigation::Navigator>(params, robot.ultrasonic);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  out.speed_m_s = params.v_max_m_s;
  return "";
}

std::string RouteRunner::begin(Plan plan, const v1::GoTo& g, uint64_t command_id, const control::Pose2& pose) {
  navigator_ = std::move(plan.navigator);
  goals_.clear();
  goal_info_.clear();
  for (const auto& p : g.points()) {
    goals_.push_back({p.x_m(), p.y_m()});
    goal_info_.push_back({p.dwell_s(), p.has_ptz(), p.ptz(), p.label()});
  }
  start_ = {pose.x_m, pose.y_m};
  dwell_left_s_ = 0.0;
  gas_hold_ = retreating_ = false;
  retreat_reason_.clear();
  goal_index_ = 0;
  command_id_ = command_id;
  switches_done_ = 0;
  twist_ = {};
  stall_clock_s_ = best_clock_s_ = 0.0;
  best_m_ = std::numeric_limits<double>::infinity();
  navigator_->setGoal(goals_.front());
  goal_distance_m_ = std::hypot(goals_.front().x - pose.x_m, goals_.front().y - pose.y_m);
  return (g.name().empty() ? "" : std::string(g.inspection() ? "inspection" : "route") + " '" + g.name() + "': ") +
         (goals_.size() == 1 ? "to " + fmtPoint(goals_[0].x, goals_[0].y) : std::to_string(goals_.size()) + " goals") +
         " at " + fmtFixed(plan.speed_m_s) + " m/s";
}

void RouteRunner::end() {
  if (navigator_) switches_done_ += navigator_->output().switch_count;
  navigator_.reset();
  command_id_ = 0;
  twist_ = {};
  dwell_left_s_ = 0.0;
  final_dwell_ = false;
  dwell_label_.clear();
  gas_hold_ = retreating_ = false;
}

void RouteRunner::arriveAt(std::size_t i, EventLog& events) {
  if (i >= goal_info_.size()) return;
  const auto& g = goal_info_[i];
  if (g.has_ptz) ptz_out_.push_back(g.ptz);
  if (g.dwell_s > 0.0) {
    dwell_left_s_ = g.dwell_s;
    dwell_label_ = g.label;
    char buf[160];
    std::snprintf(buf, sizeof buf, "inspection point %zu/%zu%s%s%s: dwelling %.1f s", i + 1, goals_.size(),
                  g.label.empty() ? "" : " '", g.label.c_str(), g.label.empty() ? "" : "'", g.dwell_s);
    std::string text = buf;
    if (g.has_ptz) {
      std::snprintf(buf, sizeof buf, ", camera pan %.0f deg tilt %.0f deg", g.ptz.pan_rad() * 180.0 / M_PI,
                    g.ptz.tilt_rad() * 180.0 / M_PI);
      text += g.ptz.home() ? ", camera home" : buf;
    }
    events.push(v1::Event::INFO, text);
  }
}

void RouteRunner::startRetreat(const std::string& why, EventLog& events) {
  // Back through the goals already reached, newest first, to the route's start.
  std::vector<navigation::Vec2> back;
  for (std::size_t i = std::min(goal_index_, goals_.size()); i-- > 0;) back.push_back(goals_[i]);
  back.push_back(start_);
  goals_ = back;
  goal_info_.assign(goals_.size(), GoalInfo{});
  goal_index_ = 0;
  dwell_left_s_ = 0.0;
  final_dwell_ = false;
  gas_hold_ = false;
  retreating_ = true;
  retreat_reason_ = why;
  navigator_->setGoal(goals_.front());
  best_m_ = std::numeric_limits<double>::infinity();
  events.push(v1::Event::INFO, why + ": retreating along the route to its start " + fmtPoint(start_.x, start_.y) +
                                   " (gas_reaction: retreat)");
}

void RouteRunner::onGasHigh(const std::string& why, GasReaction reaction, EventLog& events) {
  switch (reaction) {
    case GasReaction::kContinue:
      events.push(v1::Event::INFO, why + ": route continues (gas_reaction: continue)");
      break;
    case GasReaction::kStop:
      if (!gas_hold_ && !retreating_) {
        gas_hold_ = true;
        events.push(v1::Event::INFO, why + ": stopped and holding (gas_reaction: stop); resume continues the route, "
                                           "stop ends it");
      }
      break;
    case GasReaction::kRetreat:
      if (!retreating_) startRetreat(why, events);
      break;
  }
}

bool RouteRunner::releaseGasHold(EventLog& events) {
  if (!gas_hold_) return false;
  gas_hold_ = false;
  events.push(v1::Event::INFO, "gas hold released by operator: route continues");
  return true;
}

RouteRunner::Step RouteRunner::step(const control::Pose2& pose, const std::array<uint16_t, 4>& ultrasonic_mm,
                                    const People& people, double nav_stall_s, double dt_s, EventLog& events) {
  if (dt_s <= 0.0) return {twist_, std::nullopt};  // a command-time refresh: no tick
  if (gas_hold_ || dwell_left_s_ > 0.0) {
    // Standing still: holding after a gas alarm, or dwelling at an inspection
    // point (the dwell runs down; the stall clock does not run).
    if (!gas_hold_) dwell_left_s_ = std::max(0.0, dwell_left_s_ - dt_s);
    twist_ = {};
    if (dwell_left_s_ == 0.0 && final_dwell_ && !gas_hold_)  // the last point's dwell is over
      return {twist_, RunEnd{ackOf(command_id_, v1::Ack::COMPLETED), "route completed"}};
    return {twist_, std::nullopt};
  }
  // People are not obstacles to steer round: their echoes get the Eq 9 factor
  // (below) instead, so a worker crossing the robot's way makes it wait, not
  // detour round them along the nearest wall. Anything closer than the
  // navigator's safety distance is always kept for its AVOID mode.
  navigation::SonarRanges ranges = navigation::rangesFromMm(ultrasonic_mm);
  if (people.person_echoes) {
    const double keep_m = navigator_->params().safety_distance_m;
    for (std::size_t i = 0; i < ranges.size(); ++i)
      if ((*people.person_echoes)[i] && ranges[i] > keep_m) ranges[i] = std::numeric_limits<double>::quiet_NaN();
  }
  const navigation::NavigationOutput& out = navigator_->step(pose, ranges, dt_s);
  goal_distance_m_ = out.distance_to_goal_m;
  // Stall: no 0.1 m of progress in nav_stall_s of time the robot was allowed to move.
  stall_clock_s_ += dt_s * people.speed_factor;
  if (goal_distance_m_ < best_m_ - 0.1) {
    best_m_ = goal_distance_m_;
    best_clock_s_ = stall_clock_s_;
  } else if (stall_clock_s_ - best_clock_s_ > nav_stall_s) {
    const navigation::Vec2 g = goals_[goal_index_];
    const std::string why = "goal " + std::to_string(goal_index_ + 1) + "/" + std::to_string(goals_.size()) + " " +
                            fmtPoint(g.x, g.y) + " not reached: no progress for " +
                            std::to_string(static_cast<int>(nav_stall_s)) + " s, " + fmtFixed(goal_distance_m_) +
                            " m away";
    events.push(v1::Event::INFO, why);
    return {{}, RunEnd{ackOf(command_id_, v1::Ack::FAILED, why), "route given up"}};
  }
  if (out.mode == navigation::Mode::kAtGoal) {
    const navigation::Vec2 g = goals_[goal_index_];
    events.push(v1::Event::INFO, "goal " + std::to_string(goal_index_ + 1) + "/" + std::to_string(goals_.size()) +
                                     " " + fmtPoint(g.x, g.y) + " reached at " + fmtPoint(pose.x_m, pose.y_m));
    if (!retreating_) arriveAt(goal_index_, events);
    if (++goal_index_ < goals_.size()) {
      switches_done_ += out.switch_count;
      navigator_->setGoal(goals_[goal_index_]);  // the obstacle memory is kept
      best_m_ = std::numeric_limits<double>::infinity();
      if (dwell_left_s_ > 0.0) {
        twist_ = {};
        return {twist_, std::nullopt};
      }
    } else if (dwell_left_s_ > 0.0) {
      // The last point has a dwell: stay on it (goal_index_ = goal count), then complete.
      final_dwell_ = true;
      twist_ = {};
      return {twist_, std::nullopt};
    } else if (retreating_) {
      return {{}, RunEnd{ackOf(command_id_, v1::Ack::FAILED, "retreated to the route's start after " + retreat_reason_),
                         "retreat completed"}};
    } else {
      return {{}, RunEnd{ackOf(command_id_, v1::Ack::COMPLETED), "route completed"}};
    }
  }
  // Eq 9: people slow the robot on its way. v and w are scaled together, so
  // the path keeps its shape and a factor of 0 stops the robot.
  twist_ = {out.twist.v_m_s * people.speed_factor, out.twist.w_rad_s * people.speed_factor};
  return {twist_, std::nullopt};
}

void RouteRunner::fillTelemetry(v1::Telemetry& t, bool navigating) const {
  const bool nav = navigating && navigator_;
  t.set_nav_mode(!nav                ? ""
                 : gas_hold_         ? "GAS_HOLD"
                 : dwell_left_s_ > 0 ? "DWELL"
                 : retreating_       ? "RETREAT"
                                     : navigation::toString(navigator_->output().mode));
  // Unknown (left out) when not navigating. The message is reused tick after
  // tick (robot_app): a field that becomes unknown is cleared.
  if (nav) t.set_dwell_remaining_s(dwell_left_s_);
  else t.clear_dwell_remaining_s();
  t.set_waypoint_label(!nav                              ? ""
                       : dwell_left_s_ > 0.0             ? dwell_label_  // the point it stands at
                       : goal_index_ < goal_info_.size() ? goal_info_[goal_index_].label
                                                         : "");
  if (!goals_.empty()) t.set_goal_distance_m(goal_distance_m_);  // no route yet: unknown (left out)
  t.set_goal_index(static_cast<uint32_t>(goal_index_));
  t.set_goal_count(static_cast<uint32_t>(goals_.size()));
  t.set_nav_switches(switches_done_ + (navigator_ ? navigator_->output().switch_count : 0u));
}

}  // namespace inspect::robot
