#include "robot_client/robot_core.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>

#include "shared/fuzzy/fis_reader.hpp"
#include "shared/net/gains_proto.hpp"

namespace inspect::client {
namespace {

std::string faultName(uint32_t f) {
  switch (f) {
    case v1::FAULT_LINK_LOST: return "link lost";
    case v1::FAULT_SENSOR_STALE: return "sensor frames stale";
    case v1::FAULT_SERIAL_DOWN: return "serial device down";
    case v1::FAULT_MCU: return "MCU fault";
    case v1::FAULT_COMMAND_STALE: return "teleop set-point stale";
    default: return "fault";
  }
}

int16_t toMrad(double rad_s) {
  const double v = std::clamp(std::round(rad_s * 1000.0), -32767.0, 32767.0);
  return static_cast<int16_t>(v);
}

// "1.25" for messages.
std::string fmt2(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

// "(1.25, -0.50)" for messages.
std::string fmtPoint(double x, double y) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "(%.2f, %.2f)", x, y);
  return buf;
}

// The Ack of command `id` with `status` and, for a rejection, why.
v1::Ack ackOf(uint64_t id, v1::Ack::Status status, const std::string& reason = "") {
  v1::Ack a;
  a.set_command_id(id);
  a.set_status(status);
  if (!reason.empty()) a.set_reason(reason);
  return a;
}

// Moves `cur` toward `target` by at most `step`.
double slew(double cur, double target, double step) {
  if (target > cur + step) return cur + step;
  if (target < cur - step) return cur - step;
  return target;
}

}  // namespace

RobotCore::RobotCore(const config::RobotConfig& robot, const SafetyParams& safety,
                     const config::ControlConfig& control, std::shared_ptr<control::FuzzyGainScheduler> scheduler)
    : robot_(robot), safety_(safety), control_(control), scheduler_(std::move(scheduler)), gas_(robot.gas) {
  config::applyRobot(control_, robot_);
  gains_.fuzzy = control_.tracker.fuzzy;
  gains_.aux = control_.tracker.aux;
  events_.reserve(16);
  gas_out_.reserve(16);
}

std::vector<v1::GasChannelInfo> RobotCore::gasChannels() const {
  std::vector<v1::GasChannelInfo> out;
  for (const auto& c : gas_.config().channels) {
    v1::GasChannelInfo i;
    i.set_name(c.name);
    i.set_gas(c.gas);
    i.set_unit(c.unit);
    i.set_sensor(c.sensor);
    i.set_alarm_low(c.alarm_low);
    i.set_alarm_high(c.alarm_high);
    i.set_falling(c.direction == config::AlarmDirection::Falling);
    i.set_t90_s(c.t90_s);
    i.set_range_min(c.range_min);
    i.set_range_max(c.range_max);
    i.set_background(c.background);
    out.push_back(std::move(i));
  }
  return out;
}

std::vector<v1::Ptz> RobotCore::takePtz() {
  std::vector<v1::Ptz> out;
  out.swap(ptz_out_);
  return out;
}

void RobotCore::gasAlarmOf(const gas::AlarmTransition& t, double age_s, double now_s, v1::GasAlarm& a) const {
  const auto& ch = gas_.config().channels[static_cast<std::size_t>(t.channel)];
  a.set_id(t.id);
  a.set_channel(static_cast<uint32_t>(t.channel));
  a.set_channel_name(ch.name);
  a.set_level(t.level == gas::AlarmLevel::Low    ? v1::GasAlarm::LOW
              : t.level == gas::AlarmLevel::High ? v1::GasAlarm::HIGH
                                                 : v1::GasAlarm::SENSOR_FAULT);
  a.set_active(t.active);
  a.set_value(t.value);
  a.set_threshold(t.threshold);
  a.set_unit(ch.unit);
  // The monitor's times are on the gas clock; the message's on the robot's.
  a.set_since_us(static_cast<uint64_t>(std::max(0.0, now_s - age_s) * 1e6));
  a.set_fault(t.fault);
  a.set_peak(t.peak);
}

void RobotCore::onGasTransitions(double now_s) {
  for (const auto& t : gas_out_) {
    const auto& ch = gas_.config().channels[static_cast<std::size_t>(t.channel)];
    v1::GasAlarm a;
    gasAlarmOf(t, t.t_s - t.since_s, now_s, a);
    a.mutable_pose()->set_x_m(pose_.x_m);
    a.mutable_pose()->set_y_m(pose_.y_m);
    a.mutable_pose()->set_theta_rad(pose_.theta_rad);
    a.set_robot_time_us(static_cast<uint64_t>(now_s * 1e6));
    char text[200];
    if (t.level == gas::AlarmLevel::SensorFault)
      std::snprintf(text, sizeof text, "gas sensor %s fault %s: %s at (%.2f, %.2f)", ch.name.c_str(),
                    t.active ? "raised" : "cleared", t.fault, pose_.x_m, pose_.y_m);
    else
      std::snprintf(text, sizeof text, "gas %s %s alarm %s: %.2f %s (threshold %.2f%s) at (%.2f, %.2f)",
                    ch.name.c_str(), gas::levelName(t.level), t.active ? "raised" : "cleared", t.value,
                    ch.unit.c_str(), t.threshold, t.active ? "" : (", peak " + fmt2(t.peak)).c_str(), pose_.x_m,
                    pose_.y_m);
    events_.push_back({t.active ? v1::Event::ALARM_RAISED : v1::Event::ALARM_CLEARED, text, std::move(a)});

    // The reaction to a HIGH alarm on a route (docs/gas.md).
    if (t.level != gas::AlarmLevel::High || !t.active || mode_ != v1::NAVIGATING || !navigator_) continue;
    const std::string why = ch.name + " HIGH alarm";
    if (safety_.gas_reaction == "continue") {
      events_.push_back({v1::Event::INFO, why + ": route continues (gas_reaction: continue)"});
    } else if (safety_.gas_reaction == "stop") {
      if (!gas_hold_ && !retreating_) {
        gas_hold_ = true;
        events_.push_back({v1::Event::INFO, why + ": stopped and holding (gas_reaction: stop); resume continues "
                                                  "the route, stop ends it"});
      }
    } else if (!retreating_) {
      startRetreat(why);
    }
  }
  gas_out_.clear();
}

void RobotCore::startRetreat(const std::string& why) {
  // Back through the goals already reached, newest first, to the route's start.
  std::vector<navigation::Vec2> back;
  for (std::size_t i = std::min(goal_index_, goals_.size()); i-- > 0;) back.push_back(goals_[i]);
  back.push_back(route_start_);
  goals_ = back;
  goal_info_.assign(goals_.size(), GoalInfo{});
  goal_index_ = 0;
  dwell_left_s_ = 0.0;
  final_dwell_ = false;
  gas_hold_ = false;
  retreating_ = true;
  retreat_reason_ = why;
  navigator_->setGoal(goals_.front());
  nav_best_m_ = std::numeric_limits<double>::infinity();
  events_.push_back({v1::Event::INFO, why + ": retreating along the route to its start " +
                                          fmtPoint(route_start_.x, route_start_.y) + " (gas_reaction: retreat)"});
}

void RobotCore::arriveAt(std::size_t i) {
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
    events_.push_back({v1::Event::INFO, text});
  }
}

v1::Ack RobotCore::startTrack(const v1::Command& cmd) {
  const auto reject = [&](const std::string& why) { return ackOf(cmd.id(), v1::Ack::REJECTED, why); };
  const auto& t = cmd.track();
  applyPendingGains();
  control::TrackerParams params = control_.tracker;
  params.fuzzy = gains_.fuzzy;
  params.aux = gains_.aux;
  const std::string& c = t.controller();
  if (c == "fuzzy_pid") params.wheel_control = control::WheelControl::kFuzzyPid;
  else if (c == "pid") params.wheel_control = control::WheelControl::kPid;
  else if (c == "direct") params.wheel_control = control::WheelControl::kDirect;
  else if (!c.empty()) return reject("unknown controller '" + c + "' (fuzzy_pid, pid or direct)");
  if (params.wheel_control == control::WheelControl::kFuzzyPid && !scheduler_)
    return reject("no fuzzy-PID controller loaded on the robot");
  std::unique_ptr<control::ReferencePath> path;
  try {
    switch (t.path_case()) {
      case v1::Track::kCircle:
        path = control::makeCircle(pose_, t.circle().radius_m(), t.circle().speed_m_s(),
                                   t.circle().laps() > 0 ? t.circle().laps() : 1.0);
        break;
      case v1::Track::kLine: path = control::makeLine(pose_, t.line().length_m(), t.line().speed_m_s()); break;
      case v1::Track::kWaypoints: {
        std::vector<control::TimedWaypoint> w{{0.0, pose_.x_m, pose_.y_m}};
        const double c0 = std::cos(pose_.theta_rad), s0 = std::sin(pose_.theta_rad);
        for (const auto& p : t.waypoints().points())
          w.push_back({p.t_s(), pose_.x_m + c0 * p.x_m() - s0 * p.y_m(), pose_.y_m + s0 * p.x_m() + c0 * p.y_m()});
        path = control::makeTimedWaypoints(w);
        break;
      }
      case v1::Track::PATH_NOT_SET: return reject("no path given");
    }
  } catch (const std::invalid_argument& e) {
    return reject(e.what());
  }
  if (path->at(0).speed_m_s > robot_.limits.max_v_m_s)
    return reject("speed above the robot's limit of " + std::to_string(robot_.limits.max_v_m_s) + " m/s");
  const std::string what = path->describe();
  tracker_ = std::make_unique<control::TrajectoryTracker>(std::move(path), params, scheduler_);
  track_command_id_ = cmd.id();
  track_controller_ = control::toString(params.wheel_control);
  track_out_ = {};
  track_max_pos_m_ = track_max_ang_rad_ = 0.0;
  setpoint_ = {};
  setpoint_time_s_ = -1.0;
  setMode(v1::TRACKING, "tracking " + what + " with " + track_controller_);
  return ackOf(cmd.id(), v1::Ack::ACCEPTED);
}

v1::Ack RobotCore::stageGains(const v1::Command& cmd) {
  const auto& u = cmd.gains();
  v1::Ack ack = ackOf(cmd.id(), v1::Ack::REJECTED);
  ack.set_gains_version(gains_version_);  // the version in force now
  if (!u.has_gains()) {
    ack.set_reason("gains update without gains");
    return ack;
  }
  PendingGains p;
  p.gains = net::fromProto(u.gains());
  if (const std::string why = control::validateGains(p.gains); !why.empty()) {
    ack.set_reason("gains refused: " + why);
    return ack;
  }
  if (!u.fis().empty()) {
    if (u.fis().size() > 64 * 1024) {
      ack.set_reason("fuzzy system refused: larger than 64 KiB");
      return ack;
    }
    // Compiling a fuzzy system (its lookup surface) takes this thread tens of
    // milliseconds: not while the wheels depend on every tick.
    if (moving()) {
      ack.set_reason("fuzzy system refused: the robot is moving (" + std::string(v1::Mode_Name(mode_)) +
                     "); push it while it stands still");
      return ack;
    }
    try {
      const fuzzy::Fis fis = fuzzy::parseFis(u.fis(), "pushed fuzzy system");
      p.scheduler = std::make_shared<control::FuzzyGainScheduler>(fis, control_.use_lookup);
      p.fis_name = fis.name;
    } catch (const std::exception& e) {
      ack.set_reason(std::string("fuzzy system refused: ") + e.what());
      return ack;
    }
  }
  p.source = u.source();
  p.version = (pending_gains_ ? pending_gains_->version : gains_version_) + 1;
  // A second update before the next tick replaces the first (keeping a new
  // fuzzy system the first one brought, unless this one brings its own).
  if (pending_gains_ && !p.scheduler && pending_gains_->scheduler) {
    p.scheduler = pending_gains_->scheduler;
    p.fis_name = pending_gains_->fis_name;
  }
  pending_gains_ = std::move(p);
  ack.set_status(v1::Ack::ACCEPTED);
  ack.set_gains_version(pending_gains_->version);
  ack.set_reason("in force from the next control tick");
  return ack;
}

void RobotCore::applyPendingGains() {
  if (!pending_gains_) return;
  PendingGains p = std::move(*pending_gains_);
  pending_gains_.reset();
  gains_ = p.gains;
  gains_version_ = p.version;
  if (p.scheduler) {
    scheduler_ = p.scheduler;
    fis_name_ = p.fis_name;
  }
  if (tracker_) tracker_->setGains(gains_.fuzzy, gains_.aux, p.scheduler);
  CoreEvent e;
  e.kind = v1::Event::GAINS_APPLIED;
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "gains v%u in force%s: kp' %.4g ki' %.4g kd' %.4g ke %.4g kec %.4g k1 %.4g k2 %.4g k3 %.4g a1 %.4g "
                "a2 %.4g a3 %.4g",
                gains_version_, tracker_ ? " (also on the path being tracked)" : "", gains_.fuzzy.base.kp,
                gains_.fuzzy.base.ki, gains_.fuzzy.base.kd, gains_.fuzzy.ke, gains_.fuzzy.kec, gains_.fuzzy.k1,
                gains_.fuzzy.k2, gains_.fuzzy.k3, gains_.aux.a1, gains_.aux.a2, gains_.aux.a3);
  e.text = buf;
  if (!p.source.empty()) e.text += " from " + p.source;
  if (p.scheduler) e.text += ", fuzzy system '" + fis_name_ + "'";
  v1::Gains g;
  net::toProto(gains_, g);
  e.gains = g;
  e.gains_version = gains_version_;
  events_.push_back(std::move(e));
}

v1::Ack RobotCore::startWheelTest(const v1::Command& cmd) {
  const auto& w = cmd.wheel_test();
  std::vector<control::WheelProfileSegment> segs;
  for (int i = 0; i < w.segments_size(); ++i) {
    const auto& s = w.segments(i);
    control::WheelProfileSegment g;
    if (s.kind() == "hold") g.kind = control::WheelProfileSegment::Kind::kHold;
    else if (s.kind() == "step") g.kind = control::WheelProfileSegment::Kind::kStep;
    else if (s.kind() == "chirp") g.kind = control::WheelProfileSegment::Kind::kChirp;
    else
      return ackOf(cmd.id(), v1::Ack::REJECTED,
                   "segment " + std::to_string(i + 1) + ": unknown kind '" + s.kind() + "' (hold, step or chirp)");
    g.duration_s = s.duration_s();
    g.left_rad_s = s.left_rad_s();
    g.right_rad_s = s.right_rad_s();
    g.f0_hz = s.f0_hz();
    g.f1_hz = s.f1_hz();
    segs.push_back(g);
  }
  // The robot's speed and turn-rate limits hold for open-loop tests too.
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const auto tw = control::twistFromWheels({segs[i].left_rad_s, segs[i].right_rad_s}, robot_.geometry.wheel_radius_m,
                                             robot_.geometry.track_m);
    if (std::abs(tw.v_m_s) > robot_.limits.max_v_m_s + 1e-9 || std::abs(tw.w_rad_s) > robot_.limits.max_w_rad_s + 1e-9) {
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "segment %zu (%s): %.2f m/s and %.2f rad/s exceed the robot's limits (%.2f m/s, %.2f rad/s)", i + 1,
                    control::toString(segs[i].kind), tw.v_m_s, tw.w_rad_s, robot_.limits.max_v_m_s,
                    robot_.limits.max_w_rad_s);
      return ackOf(cmd.id(), v1::Ack::REJECTED, buf);
    }
  }
  try {
    auto profile = std::make_unique<control::WheelProfile>(std::move(segs), robot_.limits.max_wheel_speed_rad_s);
    endAutonomy();
    wheel_test_ = std::move(profile);
  } catch (const std::invalid_argument& e) {
    return ackOf(cmd.id(), v1::Ack::REJECTED, e.what());
  }
  wheel_test_id_ = cmd.id();
  wheel_test_start_ = pose_;
  wheel_test_t_s_ = 0.0;
  wheel_test_progress_ = 0.0;
  wheel_test_name_ = w.name().empty() ? "wheel test" : w.name();
  setpoint_ = {};
  setpoint_time_s_ = -1.0;
  char buf[64];
  std::snprintf(buf, sizeof buf, " (%.1f s, %d segments)", wheel_test_->duration_s(), w.segments_size());
  setMode(v1::WHEEL_TEST, wheel_test_name_ + buf);
  return ackOf(cmd.id(), v1::Ack::ACCEPTED);
}

void RobotCore::wheelTestStep(double dt_s) {
  if (!wheel_test_ || dt_s <= 0.0) return;
  // The profile is open loop and cannot steer round anything: it ends for
  // anything inside the stop distance of a front sonar, for a person close
  // enough to slow the robot (Eq 9), and once the robot is more than
  // kWheelTestRadius_m from where the test began.
  char buf[128] = "";
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < robot_.ultrasonic.mounts.size() && i < serial::kUltrasonicCount; ++i) {
    const uint16_t mm = last_frame_.ultrasonic_mm[i];
    if (std::abs(robot_.ultrasonic.mounts[i].yaw_rad) < 0.3 && mm != serial::kNoEcho)
      nearest = std::min(nearest, mm * 1e-3);
  }
  const double moved = std::hypot(pose_.x_m - wheel_test_start_.x_m, pose_.y_m - wheel_test_start_.y_m);
  if (nearest < safety_.obstacle_stop_m)
    std::snprintf(buf, sizeof buf, "%s stopped: obstacle %.2f m ahead", wheel_test_name_.c_str(), nearest);
  else if (awareness_ && awareness_->last().speed_factor < 0.999)
    std::snprintf(buf, sizeof buf, "%s stopped: a person %.2f m away", wheel_test_name_.c_str(),
                  awareness_->last().distance_m);
  else if (moved > kWheelTestRadius_m)
    std::snprintf(buf, sizeof buf, "%s stopped: %.2f m from where it began (at most %.1f m)", wheel_test_name_.c_str(),
                  moved, kWheelTestRadius_m);
  if (buf[0]) {
    acks_.push_back(ackOf(wheel_test_id_, v1::Ack::FAILED, buf));
    endAutonomy();
    cmd_wheels_ = {};
    setMode(v1::IDLE, buf);
    return;
  }
  wheel_test_t_s_ += dt_s;
  wheel_test_progress_ = std::min(1.0, wheel_test_t_s_ / wheel_test_->duration_s());
  if (wheel_test_t_s_ >= wheel_test_->duration_s()) {
    acks_.push_back(ackOf(wheel_test_id_, v1::Ack::COMPLETED));
    const std::string name = wheel_test_name_;
    endAutonomy();
    cmd_wheels_ = {};
    setMode(v1::IDLE, name + " completed");
    return;
  }
  cmd_wheels_ = wheel_test_->at(wheel_test_t_s_);
}

std::string RobotCore::autonomyRefusal() const {
  if (mode_ == v1::ESTOP) return "e-stop latched: resume first";
  if (mode_ == v1::FAILSAFE) return "failsafe latched (" + latch_reason_ + "): resume first";
  if (faults_ & v1::FAULT_SENSOR_STALE) return "sensor frames stale";
  if (faults_ & v1::FAULT_SERIAL_DOWN) return "serial device down";
  if (!have_frame_) return "no sensor frame yet: the pose is unknown";
  return "";
}

v1::Ack RobotCore::startGoTo(const v1::Command& cmd) {
  const auto reject = [&](const std::string& why) { return ackOf(cmd.id(), v1::Ack::REJECTED, why); };
  const auto& g = cmd.go_to();
  if (g.points_size() == 0) return reject("no goal given");
  if (g.points_size() > kMaxGoals)
    return reject(std::to_string(g.points_size()) + " goals: at most " + std::to_string(kMaxGoals) + " per command");
  for (int i = 0; i < g.points_size(); ++i) {
    const auto& p = g.points(i);
    if (!std::isfinite(p.x_m()) || !std::isfinite(p.y_m()))
      return reject("goal " + std::to_string(i + 1) + " has a non-finite coordinate");
    if (!std::isfinite(p.dwell_s()) || p.dwell_s() < 0.0 || p.dwell_s() > 3600.0)
      return reject("goal " + std::to_string(i + 1) + ": dwell_s must be within [0, 3600] s");
    if (p.has_ptz() && (!std::isfinite(p.ptz().pan_rad()) || !std::isfinite(p.ptz().tilt_rad()) ||
                        std::abs(p.ptz().pan_rad()) > M_PI || std::abs(p.ptz().tilt_rad()) > M_PI / 2))
      return reject("goal " + std::to_string(i + 1) + ": camera pan must be within [-pi, pi], tilt [-pi/2, pi/2]");
  }
  const double speed = g.speed_m_s();
  if (!std::isfinite(speed) || speed < 0.0) return reject("speed must be a number >= 0 m/s (0 = default)");
  if (speed > robot_.limits.max_v_m_s)
    return reject("speed " + fmt2(speed) + " m/s is above the robot's limit of " + fmt2(robot_.limits.max_v_m_s) +
                  " m/s");
  navigation::NavigationParams params;
  params.v_max_m_s = std::min(speed > 0.0 ? speed : kDefaultNavSpeed_m_s, robot_.limits.max_v_m_s);
  params.w_max_rad_s = std::min(params.w_max_rad_s, robot_.limits.max_w_rad_s);
  std::unique_ptr<navigation::Navigator> nav;
  try {
    nav = std::make_unique<navigation::Navigator>(params, robot_.ultrasonic);
  } catch (const std::invalid_argument& e) {
    return reject(e.what());
  }
  const bool was_navigating = mode_ == v1::NAVIGATING;
  endAutonomy();
  navigator_ = std::move(nav);
  goals_.clear();
  goal_info_.clear();
  for (const auto& p : g.points()) {
    goals_.push_back({p.x_m(), p.y_m()});
    goal_info_.push_back({p.dwell_s(), p.has_ptz(), p.ptz(), p.label()});
  }
  route_name_ = g.name();
  route_inspection_ = g.inspection();
  route_start_ = {pose_.x_m, pose_.y_m};
  dwell_left_s_ = 0.0;
  gas_hold_ = retreating_ = false;
  retreat_reason_.clear();
  goal_index_ = 0;
  nav_command_id_ = cmd.id();
  nav_switches_done_ = 0;
  nav_twist_ = {};
  nav_stall_clock_s_ = nav_best_clock_s_ = 0.0;
  nav_best_m_ = std::numeric_limits<double>::infinity();
  navigator_->setGoal(goals_.front());
  goal_distance_m_ = std::hypot(goals_.front().x - pose_.x_m, goals_.front().y - pose_.y_m);
  setpoint_ = {};
  setpoint_time_s_ = -1.0;
  const std::string what =
      (g.name().empty() ? "" : std::string(g.inspection() ? "inspection" : "route") + " '" + g.name() + "': ") +
      (goals_.size() == 1 ? "to " + fmtPoint(goals_[0].x, goals_[0].y)
                          : std::to_string(goals_.size()) + " goals") +
      " at " + fmt2(params.v_max_m_s) + " m/s";
  if (was_navigating) events_.push_back({v1::Event::INFO, "navigating " + what});
  setMode(v1::NAVIGATING, "navigating " + what);
  return ackOf(cmd.id(), v1::Ack::ACCEPTED);
}

void RobotCore::endAutonomy() {
  tracker_.reset();
  wheel_test_.reset();
  wheel_test_id_ = 0;
  track_command_id_ = 0;
  if (navigator_) nav_switches_done_ += navigator_->output().switch_count;
  navigator_.reset();
  nav_command_id_ = 0;
  nav_twist_ = {};
  dwell_left_s_ = 0.0;
  final_dwell_ = false;
  dwell_label_.clear();
  gas_hold_ = retreating_ = false;
}

control::Twist RobotCore::navigationTwist(double dt_s) {
  if (dt_s <= 0.0) return nav_twist_;  // a command-time refresh: no tick
  if (gas_hold_ || dwell_left_s_ > 0.0) {
    // Standing still: holding after a gas alarm, or dwelling at an inspection
    // point (the dwell runs down; the stall clock does not run).
    if (!gas_hold_) dwell_left_s_ = std::max(0.0, dwell_left_s_ - dt_s);
    nav_twist_ = {};
    if (dwell_left_s_ == 0.0 && final_dwell_ && !gas_hold_) {  // the last point's dwell is over
      acks_.push_back(ackOf(nav_command_id_, v1::Ack::COMPLETED));
      endAutonomy();
      setMode(v1::IDLE, "route completed");
    }
    return nav_twist_;
  }
  // People are not obstacles to steer round: their echoes get the Eq 9 factor
  // (below) instead, so a worker crossing the robot's way makes it wait, not
  // detour round them along the nearest wall. Anything closer than the
  // navigator's safety distance is always kept for its AVOID mode.
  navigation::SonarRanges ranges = navigation::rangesFromMm(last_frame_.ultrasonic_mm);
  if (awareness_) {
    const auto& person = awareness_->tracker().personEchoes();
    const double keep_m = navigator_->params().safety_distance_m;
    for (std::size_t i = 0; i < ranges.size(); ++i)
      if (person[i] && ranges[i] > keep_m) ranges[i] = std::numeric_limits<double>::quiet_NaN();
  }
  const navigation::NavigationOutput& out = navigator_->step(pose_, ranges, dt_s);
  goal_distance_m_ = out.distance_to_goal_m;
  // Stall: no 0.1 m of progress in nav_stall_s of time the robot was allowed to move.
  const double allowed = awareness_ ? awareness_->last().speed_factor : 1.0;
  nav_stall_clock_s_ += dt_s * allowed;
  if (goal_distance_m_ < nav_best_m_ - 0.1) {
    nav_best_m_ = goal_distance_m_;
    nav_best_clock_s_ = nav_stall_clock_s_;
  } else if (nav_stall_clock_s_ - nav_best_clock_s_ > safety_.nav_stall_s) {
    const navigation::Vec2 g = goals_[goal_index_];
    const std::string why = "goal " + std::to_string(goal_index_ + 1) + "/" + std::to_string(goals_.size()) + " " +
                            fmtPoint(g.x, g.y) + " not reached: no progress for " +
                            std::to_string(static_cast<int>(safety_.nav_stall_s)) + " s, " + fmt2(goal_distance_m_) +
                            " m away";
    acks_.push_back(ackOf(nav_command_id_, v1::Ack::FAILED, why));
    events_.push_back({v1::Event::INFO, why});
    endAutonomy();
    setMode(v1::IDLE, "route given up");
    return {};
  }
  if (out.mode == navigation::Mode::kAtGoal) {
    const navigation::Vec2 g = goals_[goal_index_];
    events_.push_back({v1::Event::INFO, "goal " + std::to_string(goal_index_ + 1) + "/" +
                                            std::to_string(goals_.size()) + " " + fmtPoint(g.x, g.y) +
                                            " reached at " + fmtPoint(pose_.x_m, pose_.y_m)});
    if (!retreating_) arriveAt(goal_index_);
    if (++goal_index_ < goals_.size()) {
      nav_switches_done_ += out.switch_count;
      navigator_->setGoal(goals_[goal_index_]);  // the obstacle memory is kept
      nav_best_m_ = std::numeric_limits<double>::infinity();
      if (dwell_left_s_ > 0.0) {
        nav_twist_ = {};
        return nav_twist_;
      }
    } else if (dwell_left_s_ > 0.0) {
      // The last point has a dwell: stay on it (goal_index_ = goal count), then complete.
      final_dwell_ = true;
      nav_twist_ = {};
      return nav_twist_;
    } else {
      if (retreating_) {
        acks_.push_back(ackOf(nav_command_id_, v1::Ack::FAILED, "retreated to the route's start after " +
                                                                    retreat_reason_));
        endAutonomy();
        setMode(v1::IDLE, "retreat completed");
        return {};
      }
      acks_.push_back(ackOf(nav_command_id_, v1::Ack::COMPLETED));
      endAutonomy();
      setMode(v1::IDLE, "route completed");
      return {};
    }
  }
  // Eq 9: people slow the robot on its way. v and w are scaled together, so
  // the path keeps its shape and a factor of 0 stops the robot.
  const double factor = awareness_ ? awareness_->last().speed_factor : 1.0;
  nav_twist_ = {out.twist.v_m_s * factor, out.twist.w_rad_s * factor};
  return nav_twist_;
}

void RobotCore::setMode(v1::Mode m, const std::string& why) {
  if (m == mode_) return;
  mode_ = m;
  events_.push_back({v1::Event::MODE_CHANGE, std::string(v1::Mode_Name(m)) + ": " + why});
}

void RobotCore::raise(uint32_t fault, const std::string& why) {
  if (faults_ & fault) return;
  faults_ |= fault;
  events_.push_back({v1::Event::FAULT_RAISED, faultName(fault) + (why.empty() ? "" : ": " + why)});
}

void RobotCore::clear(uint32_t fault, const std::string& why) {
  if (!(faults_ & fault)) return;
  faults_ &= ~fault;
  events_.push_back({v1::Event::FAULT_CLEARED, faultName(fault) + (why.empty() ? "" : ": " + why)});
}

void RobotCore::latchFailsafe(const std::string& why) {
  setpoint_ = {};
  setpoint_time_s_ = -1.0;
  endAutonomy();
  if (mode_ == v1::ESTOP || mode_ == v1::FAILSAFE) return;
  latch_reason_ = why;
  setMode(v1::FAILSAFE, why + "; needs resume");
}

void RobotCore::onLinkUp(double now_s) {
  link_up_ = true;
  last_link_activity_s_ = now_s;
  clear(v1::FAULT_LINK_LOST, "link restored");
}

void RobotCore::onLinkDown(double /*now_s*/, const std::string& why) {
  link_up_ = false;
  raise(v1::FAULT_LINK_LOST, why);
  if (movingAtLinkLoss()) latchFailsafe("link lost");
  setpoint_ = {};
  setpoint_time_s_ = -1.0;
}

void RobotCore::onLinkActivity(double now_s) {
  // A message after a silence that no timer saw in time (this process was
  // stalled, or its loop was late) still ends the silence as a link loss.
  checkLinkSilence(now_s);
  last_link_activity_s_ = now_s;
  if (link_up_) clear(v1::FAULT_LINK_LOST, "link restored");
}

void RobotCore::onSerialState(bool open, double /*now_s*/) {
  serial_open_ = open;
  if (open) {
    clear(v1::FAULT_SERIAL_DOWN, "");
  } else {
    raise(v1::FAULT_SERIAL_DOWN, "");
    have_frame_ = false;
    if (moving()) latchFailsafe("serial device down");
  }
}

void RobotCore::setSerialCounters(const serial::DecoderCounters& rx, uint64_t bytes_tx, uint64_t frames_tx) {
  serial_rx_ = rx;
  bytes_tx_ = bytes_tx;
  frames_tx_ = frames_tx;
}

v1::Ack RobotCore::onCommand(const v1::Command& cmd, double now_s) {
  // Timeouts that fell due before this command first (after a stall of this
  // process the command may be handled before the timer and the frames).
  checkTimeouts(now_s);
  onLinkActivity(now_s);
  v1::Ack ack;
  ack.set_command_id(cmd.id());
  last_command_id_ = cmd.id();
  auto reject = [&](const std::string& why) {
    ack.set_status(v1::Ack::REJECTED);
    ack.set_reason(why);
    return ack;
  };
  switch (cmd.kind_case()) {
    case v1::Command::kTeleop: {
      const double v = cmd.teleop().v_m_s(), w = cmd.teleop().w_rad_s();
      if (!std::isfinite(v) || !std::isfinite(w)) return reject("non-finite velocity");
      if (mode_ == v1::ESTOP) return reject("e-stop latched: resume first");
      if (mode_ == v1::FAILSAFE) return reject("failsafe latched (" + latch_reason_ + "): resume first");
      if (faults_ & v1::FAULT_SENSOR_STALE) return reject("sensor frames stale");
      if (faults_ & v1::FAULT_SERIAL_DOWN) return reject("serial device down");
      setpoint_ = {std::clamp(v, -robot_.limits.max_v_m_s, robot_.limits.max_v_m_s),
                   std::clamp(w, -robot_.limits.max_w_rad_s, robot_.limits.max_w_rad_s)};
      setpoint_time_s_ = now_s;
      clear(v1::FAULT_COMMAND_STALE, "");
      endAutonomy();  // the operator takes over
      setMode(v1::TELEOP, "teleop set-point");
      ack.set_status(v1::Ack::ACCEPTED);
      if (setpoint_.v_m_s != v || setpoint_.w_rad_s != w) ack.set_reason("clamped to the robot's limits");
      return ack;
    }
    case v1::Command::kTrack:
      if (const std::string why = autonomyRefusal(); !why.empty()) return reject(why);
      return startTrack(cmd);
    case v1::Command::kGoTo:
      if (const std::string why = autonomyRefusal(); !why.empty()) return reject(why);
      return startGoTo(cmd);
    case v1::Command::kWheelTest:
      if (const std::string why = autonomyRefusal(); !why.empty()) return reject(why);
      return startWheelTest(cmd);
    case v1::Command::kGains: return stageGains(cmd);
    case v1::Command::kStop:
      setpoint_ = {};
      setpoint_time_s_ = -1.0;
      endAutonomy();
      if (moving()) setMode(v1::IDLE, "stop");
      ack.set_status(v1::Ack::ACCEPTED);
      return ack;
    case v1::Command::kEstop:
      setpoint_ = {};
      setpoint_time_s_ = -1.0;
      endAutonomy();
      latch_reason_ = "e-stop";
      setMode(v1::ESTOP, "e-stop from operator; needs resume");
      ack.set_status(v1::Ack::ACCEPTED);
      return ack;
    case v1::Command::kResume:
      if (mode_ == v1::NAVIGATING && gas_hold_) {
        gas_hold_ = false;
        events_.push_back({v1::Event::INFO, "gas hold released by operator: route continues"});
      }
      if (mode_ == v1::ESTOP || mode_ == v1::FAILSAFE) {
        if (faults_ & v1::FAULT_SENSOR_STALE) return reject("sensor frames still stale");
        if (faults_ & v1::FAULT_SERIAL_DOWN) return reject("serial device still down");
        latch_reason_.clear();
        setMode(v1::IDLE, "resumed by operator");
      }
      ack.set_status(v1::Ack::ACCEPTED);
      return ack;
    case v1::Command::kVideo:
    case v1::Command::kPtz:
      return reject("camera commands are handled by the robot's video sender, not the motion core");
    case v1::Command::KIND_NOT_SET: break;
  }
  return reject("unknown or empty command");
}

void RobotCore::checkLinkSilence(double now_s) {
  // Tests the bit first so that no string is built on every tick.
  if (link_up_ && !(faults_ & v1::FAULT_LINK_LOST) && now_s - last_link_activity_s_ > safety_.link_timeout_s) {
    raise(v1::FAULT_LINK_LOST, "no heartbeat or command for " +
                                   std::to_string(static_cast<int>(safety_.link_timeout_s * 1000)) + " ms");
    if (movingAtLinkLoss()) latchFailsafe("link lost");
  }
}

void RobotCore::checkTimeouts(double now_s) {
  checkLinkSilence(now_s);
  if (mode_ == v1::TELEOP && setpoint_time_s_ >= 0 && now_s - setpoint_time_s_ > safety_.command_timeout_s) {
    raise(v1::FAULT_COMMAND_STALE, "");
    setpoint_ = {};
    setpoint_time_s_ = -1.0;
    // With both timeouts at 300 ms, the set-point of a robot whose link went
    // silent usually expires first (the last message was a heartbeat): the
    // link loss that follows must still latch FAILSAFE, or the robot would
    // drive on when the link comes back with the console still re-sending.
    stale_stop_s_ = now_s;
    setMode(v1::IDLE, "teleop set-point stale");
  }
  if (have_frame_ && !(faults_ & v1::FAULT_SENSOR_STALE) && now_s - last_frame_s_ > safety_.sensor_timeout_s) {
    raise(v1::FAULT_SENSOR_STALE, "");
    if (moving()) latchFailsafe("sensor frames stale");
  }
}

double RobotCore::obstacleFactor() {
  const double stop = safety_.obstacle_stop_m, slow = safety_.obstacle_slow_m;
  if (!(slow > stop) || !have_frame_) return 1.0;
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < robot_.ultrasonic.mounts.size() && i < serial::kUltrasonicCount; ++i) {
    const uint16_t mm = last_frame_.ultrasonic_mm[i];
    if (std::abs(robot_.ultrasonic.mounts[i].yaw_rad) < 0.3 && mm != serial::kNoEcho)
      nearest = std::min(nearest, mm * 1e-3);
  }
  const double f = std::clamp((nearest - stop) / (slow - stop), 0.0, 1.0);
  if (f == 0.0 && !obstacle_stopped_)
    events_.push_back({v1::Event::INFO, "obstacle " + std::to_string(static_cast<int>(nearest * 100)) +
                                            " cm ahead: stopped on the path until it clears"});
  obstacle_stopped_ = f == 0.0;
  return f;
}

serial::WheelCommand RobotCore::computeCommand(double dt_s) {
  const bool latched = mode_ == v1::ESTOP || mode_ == v1::FAILSAFE;
  if (mode_ == v1::WHEEL_TEST && !latched && !(faults_ & v1::FAULT_SENSOR_STALE)) {
    // Open loop: the profile's set-points go to the MCU unslewed (the steps
    // are the point); the MCU clamps to its wheel limit.
    wheelTestStep(dt_s);
    return wheelCommand(true);
  }
  if (mode_ == v1::TRACKING && tracker_ && !latched && !(faults_ & v1::FAULT_SENSOR_STALE)) {
    if (dt_s > 0.0) {
      // Eq 9: people slow the robot down on its path; anything close ahead stops it.
      const double factor = std::min(awareness_ ? awareness_->last().speed_factor : 1.0, obstacleFactor());
      track_out_ = tracker_->step(pose_, measured_, factor, dt_s);
      track_max_pos_m_ = std::max(track_max_pos_m_, track_out_.error.position_m());
      track_max_ang_rad_ = std::max(track_max_ang_rad_, std::abs(track_out_.error.theta_rad));
      track_gains_ = tracker_->lastGains(0);
      cmd_wheels_ = track_out_.command;  // the tracker's own loop shapes the command
      if (track_out_.done) {
        acks_.push_back(ackOf(track_command_id_, v1::Ack::COMPLETED));
        endAutonomy();
        cmd_wheels_ = {};
        setMode(v1::IDLE, "path completed");
      }
    }
    return wheelCommand(true);
  }
  control::Twist target;
  if (mode_ == v1::TELEOP) target = setpoint_;
  else if (mode_ == v1::NAVIGATING && navigator_ && !latched && !(faults_ & v1::FAULT_SENSOR_STALE))
    target = navigationTwist(dt_s);
  target = control::limitTwist(target, robot_.geometry.wheel_radius_m, robot_.geometry.track_m,
                               robot_.limits.max_wheel_speed_rad_s);
  const auto want = control::wheelsFromTwist(target, robot_.geometry.wheel_radius_m, robot_.geometry.track_m);
  if (latched || (faults_ & v1::FAULT_SENSOR_STALE)) {
    cmd_wheels_ = {};  // safety stops are immediate, not slew-limited
  } else {
    // Normal starts and stops ramp symmetrically, so a timed teleop segment
    // covers exactly v * T; navigation is slewed the same way.
    const double step = robot_.limits.max_wheel_accel_rad_s2 * std::clamp(dt_s, 0.0, 0.05);
    cmd_wheels_.left_rad_s = slew(cmd_wheels_.left_rad_s, want.left_rad_s, step);
    cmd_wheels_.right_rad_s = slew(cmd_wheels_.right_rad_s, want.right_rad_s, step);
  }
  return wheelCommand(!latched);
}

serial::WheelCommand RobotCore::wheelCommand(bool enable) {
  cmd_twist_ = control::twistFromWheels(cmd_wheels_, robot_.geometry.wheel_radius_m, robot_.geometry.track_m);
  serial::WheelCommand c;
  c.left_mrad_s = toMrad(cmd_wheels_.left_rad_s);
  c.right_mrad_s = toMrad(cmd_wheels_.right_rad_s);
  c.flags = enable ? serial::WheelCommand::kEnable : 0;
  return c;
}

serial::WheelCommand RobotCore::onSensorFrame(const serial::SensorFrame& f, double now_s) {
  // The frames were stale if this one comes too late, whether or not the
  // timer saw it (after a stall of this process the backlog of old frames may
  // be read before the timer runs): latch before accepting it.
  checkTimeouts(now_s);
  double dt_s = 0.01;
  if (!have_frame_) {
    // First frame after start or after the serial line came back: re-anchor
    // displacement; the heading reference is taken once per process.
    if (last_frame_s_ < 0) heading0_ = f.heading_0p1mrad;
    last_disp_ = f.wheel_disp_0p1mm;
    // After an outage the MCU clock restarts the count: carry the outage's
    // length over, so a series sampled on mcu_time_us shows the gap.
    if (last_frame_s_ >= 0) mcu_time_us_ += static_cast<uint64_t>(std::max(0.0, now_s - last_frame_s_) * 1e6);
  } else {
    dt_s = static_cast<double>(static_cast<uint32_t>(f.mcu_time_ms - last_mcu_ms_)) / 1000.0;
    mcu_time_us_ += static_cast<uint64_t>(static_cast<uint32_t>(f.mcu_time_ms - last_mcu_ms_)) * 1000u;
    const double dl = static_cast<int32_t>(static_cast<uint32_t>(f.wheel_disp_0p1mm[0]) -
                                           static_cast<uint32_t>(last_disp_[0])) * 1e-4;
    const double dr = static_cast<int32_t>(static_cast<uint32_t>(f.wheel_disp_0p1mm[1]) -
                                           static_cast<uint32_t>(last_disp_[1])) * 1e-4;
    last_disp_ = f.wheel_disp_0p1mm;
    pose_ = control::odometryWithHeading(pose_, dl, dr, (f.heading_0p1mrad - heading0_) * 1e-4);
  }
  have_frame_ = true;
  last_frame_s_ = now_s;
  if (awareness_) {
    mcu_clock_s_ += std::clamp(dt_s, 0.0, 0.1);
    std::array<double, 4> ranges{};
    for (std::size_t i = 0; i < 4; ++i)
      ranges[i] = f.ultrasonic_mm[i] == serial::kNoEcho ? -1.0 : f.ultrasonic_mm[i] * 1e-3;
    awareness_->step(pose_, ranges, mcu_clock_s_);
  }
  last_mcu_ms_ = f.mcu_time_ms;
  last_frame_ = f;
  // Gas alarms run on the MCU's clock (like the people tracker), so that
  // durations mean the same when the simulator runs faster than real time.
  gas_clock_s_ += std::clamp(dt_s, 0.0, 0.1);
  gas_.update(f.gas_raw, gas_clock_s_, gas_out_);
  if (!gas_out_.empty()) onGasTransitions(now_s);
  measured_ = {f.wheel_speed_mrad_s[0] * 1e-3, f.wheel_speed_mrad_s[1] * 1e-3};
  clear(v1::FAULT_SENSOR_STALE, "");
  constexpr uint16_t kSerious = serial::kFaultMotorDriver | serial::kFaultEStopButton;
  if ((f.faults & kSerious) && !(faults_ & v1::FAULT_MCU)) {
    raise(v1::FAULT_MCU, "MCU fault flags 0x" + std::to_string(f.faults));
    if (moving()) latchFailsafe("MCU fault");
  } else if (!(f.faults & kSerious)) {
    clear(v1::FAULT_MCU, "");
  }
  if (++rate_count_, now_s - rate_window_start_s_ >= 1.0) {
    sensor_rate_hz_ = rate_count_ / (now_s - rate_window_start_s_);
    rate_window_start_s_ = now_s;
    rate_count_ = 0;
  }
  checkTimeouts(now_s);
  applyPendingGains();  // the tick boundary: staged gains go into force together
  return computeCommand(dt_s);
}

serial::WheelCommand RobotCore::commandNow() { return computeCommand(0.0); }

std::optional<serial::WheelCommand> RobotCore::onTimer(double now_s) {
  const v1::Mode before = mode_;
  checkTimeouts(now_s);
  // No frames (stale, or the serial device closed after frames had come): no
  // gas readings either - the channels go to no_data after 0.5 s.
  if ((faults_ & (v1::FAULT_SENSOR_STALE | v1::FAULT_SERIAL_DOWN)) && last_frame_s_ >= 0.0) {
    gas_.noFrames(gas_clock_s_ + (now_s - last_frame_s_), gas_out_);
    if (!gas_out_.empty()) onGasTransitions(now_s);
  }
  if (faults_ & v1::FAULT_SENSOR_STALE) return computeCommand(0.01);
  // A latch (link loss) stops the wheels now, not at the next sensor frame.
  if (mode_ != before && (mode_ == v1::FAILSAFE || mode_ == v1::ESTOP)) return computeCommand(0.0);
  return std::nullopt;
}

void RobotCore::fillTelemetry(v1::Telemetry& t, double now_s) const {
  t.set_robot_time_us(static_cast<uint64_t>(now_s * 1e6));
  auto* p = t.mutable_pose();
  p->set_x_m(pose_.x_m);
  p->set_y_m(pose_.y_m);
  p->set_theta_rad(pose_.theta_rad);
  t.set_gains_version(gains_version_);
  t.set_mcu_time_us(mcu_time_us_);
  t.set_wheel_test_progress(wheel_test_progress_);
  t.set_wheel_left_rad_s(measured_.left_rad_s);
  t.set_wheel_right_rad_s(measured_.right_rad_s);
  t.set_cmd_wheel_left_rad_s(cmd_wheels_.left_rad_s);
  t.set_cmd_wheel_right_rad_s(cmd_wheels_.right_rad_s);
  const auto tw = control::twistFromWheels(measured_, robot_.geometry.wheel_radius_m, robot_.geometry.track_m);
  t.set_v_m_s(tw.v_m_s);
  t.set_w_rad_s(tw.w_rad_s);
  t.set_cmd_v_m_s(cmd_twist_.v_m_s);
  t.set_cmd_w_rad_s(cmd_twist_.w_rad_s);
  t.clear_ultrasonic_m();
  for (uint16_t mm : last_frame_.ultrasonic_mm) t.add_ultrasonic_m(mm == serial::kNoEcho ? -1.0 : mm * 1e-3);
  t.set_grayscale(last_frame_.grayscale);
  t.clear_gas();
  for (int i = 0; i < gas_.channels(); ++i) t.add_gas(gas_.value(i));  // NaN = no data
  t.clear_active_alarms();
  gas_active_.clear();  // reused: no allocation per telemetry message once grown
  gas_.active(gas_active_);
  for (const auto& a : gas_active_) gasAlarmOf(a, gas_clock_s_ - a.since_s, now_s, *t.add_active_alarms());
  t.set_battery_v(last_frame_.battery_mv * 1e-3);
  t.set_mode(mode_);
  t.set_faults(faults_);
  t.set_mcu_faults(last_frame_.faults);
  auto* s = t.mutable_serial();
  s->set_frames_ok(serial_rx_.frames_ok);
  s->set_bad_cobs(serial_rx_.bad_cobs);
  s->set_bad_crc(serial_rx_.bad_crc);
  s->set_bad_length(serial_rx_.bad_length);
  s->set_unknown_id(serial_rx_.unknown_id);
  s->set_seq_gaps(serial_rx_.seq_gaps);
  s->set_overflow(serial_rx_.overflow);
  s->set_bytes_rx(serial_rx_.bytes_rx);
  s->set_bytes_tx(bytes_tx_);
  s->set_frames_tx(frames_tx_);
  t.set_sensor_rate_hz(have_frame_ ? sensor_rate_hz_ : 0.0);
  t.set_last_command_id(last_command_id_);
  auto* ref = t.mutable_reference();
  ref->set_x_m(track_out_.ref.pose.x_m);
  ref->set_y_m(track_out_.ref.pose.y_m);
  ref->set_theta_rad(track_out_.ref.pose.theta_rad);
  t.set_position_error_m(track_out_.error.position_m());
  t.set_angle_error_rad(std::abs(track_out_.error.theta_rad));
  t.set_track_progress(tracker_ && tracker_->path().length_m() > 0
                           ? tracker_->progress().s_m / tracker_->path().length_m()
                           : (track_out_.done ? 1.0 : 0.0));
  t.set_track_max_position_error_m(track_max_pos_m_);
  t.set_track_max_angle_error_rad(track_max_ang_rad_);
  t.set_kp(track_gains_.kp);
  t.set_ki(track_gains_.ki);
  t.set_kd(track_gains_.kd);
  t.set_track_controller(tracker_ ? track_controller_ : std::string());
  const bool nav = mode_ == v1::NAVIGATING && navigator_;
  t.set_nav_mode(!nav              ? ""
                 : gas_hold_       ? "GAS_HOLD"
                 : dwell_left_s_ > 0 ? "DWELL"
                 : retreating_     ? "RETREAT"
                                   : navigation::toString(navigator_->output().mode));
  t.set_dwell_remaining_s(nav ? dwell_left_s_ : 0.0);
  t.set_waypoint_label(!nav                ? ""
                       : dwell_left_s_ > 0.0 ? dwell_label_  // the point it stands at
                       : goal_index_ < goal_info_.size() ? goal_info_[goal_index_].label
                                                         : "");
  t.set_goal_distance_m(goal_distance_m_);
  t.set_goal_index(static_cast<uint32_t>(goal_index_));
  t.set_goal_count(static_cast<uint32_t>(goals_.size()));
  t.set_nav_switches(nav_switches_done_ + (navigator_ ? navigator_->output().switch_count : 0u));
  if (awareness_) {
    const auto& a = awareness_->last();
    t.set_pattern(static_cast<v1::HumanPattern>(static_cast<int>(a.pattern)));
    t.set_nearest_person_m(a.distance_m);
    t.set_nearest_person_speed_m_s(a.person_speed_m_s);
    t.set_speed_factor(a.speed_factor);
    t.set_people_tracked(static_cast<uint32_t>(a.people));
  } else {
    t.set_nearest_person_m(-1.0);
    t.set_speed_factor(1.0);
  }
}

std::vector<v1::Ack> RobotCore::takeAcks() {
  std::vector<v1::Ack> out;
  out.swap(acks_);
  return out;
}

std::vector<CoreEvent> RobotCore::takeEvents() {
  std::vector<CoreEvent> out;
  out.swap(events_);
  events_.reserve(16);
  return out;
}

}  // namespace inspect::client
