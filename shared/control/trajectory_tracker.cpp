#include "shared/control/trajectory_tracker.hpp"

#include <algorithm>
#include <stdexcept>

namespace inspect::control {

const char* toString(WheelControl c) {
  switch (c) {
    case WheelControl::kDirect: return "direct";
    case WheelControl::kPid: return "pid";
    case WheelControl::kFuzzyPid: return "fuzzy_pid";
  }
  return "?";
}

TrajectoryTracker::TrajectoryTracker(std::unique_ptr<ReferencePath> path, const TrackerParams& params,
                                     std::shared_ptr<FuzzyGainScheduler> scheduler)
    : path_(std::move(path)), p_(params), sched_(std::move(scheduler)) {
  if (!path_) throw std::invalid_argument("tracker needs a path");
  if (p_.wheel_control == WheelControl::kFuzzyPid && !sched_)
    throw std::invalid_argument("fuzzy-PID wheel control needs the fuzzy gain scheduler");
  p_.pid.output_min = -p_.max_wheel_speed_rad_s;
  p_.pid.output_max = p_.max_wheel_speed_rad_s;
}

void TrajectoryTracker::setGains(const FuzzyPidParams& fuzzy, const AuxiliaryGains& aux,
                                 std::shared_ptr<FuzzyGainScheduler> scheduler) {
  p_.fuzzy = fuzzy;
  p_.aux = aux;
  if (scheduler) sched_ = std::move(scheduler);
}

PidGains TrajectoryTracker::lastGains(int wheel) const {
  return p_.wheel_control == WheelControl::kFuzzyPid ? wheel_[wheel].gains : p_.fuzzy.base;
}

double TrajectoryTracker::wheelStep(int i, double ref, double meas, double dt_s) {
  const double ff = p_.feedforward ? ref : 0.0;
  PidConfig cfg = p_.pid;
  // With feed-forward the controller only corrects: its output range is what
  // is left of the wheel's range.
  cfg.output_min = -p_.max_wheel_speed_rad_s - ff;
  cfg.output_max = p_.max_wheel_speed_rad_s - ff;
  double u = 0.0;
  switch (p_.wheel_control) {
    case WheelControl::kDirect: return std::clamp(ref, -p_.max_wheel_speed_rad_s, p_.max_wheel_speed_rad_s);
    case WheelControl::kPid:
      u = pidStep(cfg, p_.fuzzy.base, wheel_[i].pid, ref, meas, dt_s);
      break;
    case WheelControl::kFuzzyPid:
      u = fuzzyPidStep(*sched_, p_.fuzzy, cfg, wheel_[i], ref, meas, dt_s);
      break;
  }
  return std::clamp(ff + u, -p_.max_wheel_speed_rad_s, p_.max_wheel_speed_rad_s);
}

TrackerOutput TrajectoryTracker::step(const Pose2& pose, const WheelSpeeds& measured, double speed_factor,
                                      double dt_s) {
  TrackerOutput out;
  out.ref = advance(*path_, progress_, speed_factor, dt_s);
  if (speed_factor < 1.0 && !progress_.done) {
    // Slowed or stopped for a person: the robot may be ahead of a reference
    // that slowed faster than the motors could (tau 0.2 s). Move the reference
    // up to the robot instead of backing the robot up towards someone.
    const double ahead = std::cos(out.ref.pose.theta_rad) * (pose.x_m - out.ref.pose.x_m) +
                         std::sin(out.ref.pose.theta_rad) * (pose.y_m - out.ref.pose.y_m);
    if (ahead > 0.0) {
      progress_.s_m = std::min(progress_.s_m + ahead, path_->length_m());
      out.ref = advance(*path_, progress_, speed_factor, 0.0);
    }
  }
  out.error = trackingError(pose, out.ref.pose);  // Eq 10
  out.done = progress_.done;
  if (out.done) return out;  // zero command: the path is complete
  out.twist = auxiliaryControl(out.error, out.ref, p_.aux);  // Eq 12
  out.twist = limitTwist(out.twist, p_.wheel_radius_m, p_.track_m, p_.max_wheel_speed_rad_s);
  out.reference = wheelsFromTwist(out.twist, p_.wheel_radius_m, p_.track_m);  // Eq 13
  out.command.left_rad_s = wheelStep(0, out.reference.left_rad_s, measured.left_rad_s, dt_s);
  out.command.right_rad_s = wheelStep(1, out.reference.right_rad_s, measured.right_rad_s, dt_s);
  return out;
}

}  // namespace inspect::control
