#include "shared/robot/track_runner.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace inspect::robot {

std::string TrackRunner::start(const v1::Track& t, uint64_t command_id, const control::Pose2& pose,
                               const config::ControlConfig& control, const control::GainSet& gains,
                               const std::shared_ptr<control::FuzzyGainScheduler>& scheduler,
                               const config::RobotLimits& limits, std::string& what) {
  control::TrackerParams params = control.tracker;
  params.fuzzy = gains.fuzzy;
  params.aux = gains.aux;
  const std::string& c = t.controller();
  if (c == "fuzzy_pid") params.wheel_control = control::WheelControl::kFuzzyPid;
  else if (c == "pid") params.wheel_control = control::WheelControl::kPid;
  else if (c == "direct") params.wheel_control = control::WheelControl::kDirect;
  else if (!c.empty()) return "unknown controller '" + c + "' (fuzzy_pid, pid or direct)";
  if (params.wheel_control == control::WheelControl::kFuzzyPid && !scheduler)
    return "no fuzzy-PID controller loaded on the robot";
  std::unique_ptr<control::ReferencePath> path;
  try {
    switch (t.path_case()) {
      case v1::Track::kCircle:
        path = control::makeCircle(pose, t.circle().radius_m(), t.circle().speed_m_s(),
                                   t.circle().laps() > 0 ? t.circle().laps() : 1.0);
        break;
      case v1::Track::kLine: path = control::makeLine(pose, t.line().length_m(), t.line().speed_m_s()); break;
      case v1::Track::kWaypoints: {
        std::vector<control::TimedWaypoint> w{{0.0, pose.x_m, pose.y_m}};
        const double c0 = std::cos(pose.theta_rad), s0 = std::sin(pose.theta_rad);
        for (const auto& p : t.waypoints().points())
          w.push_back({p.t_s(), pose.x_m + c0 * p.x_m() - s0 * p.y_m(), pose.y_m + s0 * p.x_m() + c0 * p.y_m()});
        path = control::makeTimedWaypoints(w);
        break;
      }
      case v1::Track::PATH_NOT_SET: return "no path given";
    }
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  if (path->at(0).speed_m_s > limits.max_v_m_s)
    return "speed above the robot's limit of " + std::to_string(limits.max_v_m_s) + " m/s";
  const std::string described = path->describe();
  tracker_ = std::make_unique<control::TrajectoryTracker>(std::move(path), params, scheduler);
  command_id_ = command_id;
  controller_ = control::toString(params.wheel_control);
  out_ = {};
  max_pos_m_ = max_ang_rad_ = 0.0;
  ran_ = true;
  what = described + " with " + controller_;
  return "";
}

std::optional<RunEnd> TrackRunner::step(const control::Pose2& pose, const control::WheelSpeeds& measured,
                                        double factor, double dt_s) {
  out_ = tracker_->step(pose, measured, factor, dt_s);
  max_pos_m_ = std::max(max_pos_m_, out_.error.position_m());
  max_ang_rad_ = std::max(max_ang_rad_, std::abs(out_.error.theta_rad));
  gains_ = tracker_->lastGains(0);
  if (!out_.done) return std::nullopt;
  return RunEnd{ackOf(command_id_, v1::Ack::COMPLETED), "path completed"};
}

void TrackRunner::setGains(const control::GainSet& gains,
                           const std::shared_ptr<control::FuzzyGainScheduler>& scheduler) {
  if (tracker_) tracker_->setGains(gains.fuzzy, gains.aux, scheduler);
}

void TrackRunner::fillTelemetry(v1::Telemetry& t) const {
  if (!ran_) return;  // no run yet: reference, errors, progress and gains unknown
  auto* ref = t.mutable_reference();
  ref->set_x_m(out_.ref.pose.x_m);
  ref->set_y_m(out_.ref.pose.y_m);
  ref->set_theta_rad(out_.ref.pose.theta_rad);
  t.set_position_error_m(out_.error.position_m());
  t.set_angle_error_rad(std::abs(out_.error.theta_rad));
  t.set_track_progress(tracker_ && tracker_->path().length_m() > 0
                           ? tracker_->progress().s_m / tracker_->path().length_m()
                           : (out_.done ? 1.0 : 0.0));
  t.set_track_max_position_error_m(max_pos_m_);
  t.set_track_max_angle_error_rad(max_ang_rad_);
  t.set_kp(gains_.kp);
  t.set_ki(gains_.ki);
  t.set_kd(gains_.kd);
  t.set_track_controller(tracker_ ? controller_ : std::string());
}

}  // namespace inspect::robot
