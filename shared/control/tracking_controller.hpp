#pragma once
// Trajectory tracking: the paper's error (Eq 10) and auxiliary kinematic
// controller (Eq 12). Pure functions.
//
// Eq 12 as printed, v = v_k cos(th_e) + a1 v_e, w = w_k + a2 v_r sin(th_e) + a3 w_e,
// leaves v_k, w_k, v_e, w_e undefined. We read it as the classic Kanayama
// tracking law written with the paper's error sign (actual - reference, in the
// robot frame, Eq 10): v_k = v_r, w_k = w_r, v_e = x_e, w_e = y_e:
//   v = v_r cos(th_e) + a1 x_e
//   w = w_r + a2 v_r sin(th_e) + a3 y_e
// with a1 = -1, a2 = -1.2, a3 = -0.5 (negative because the errors are
// actual - reference). This is Kanayama's law with Kx = 1, Ktheta = 1.2,
// Ky v_r = 0.5, which is asymptotically stable for v_r > 0 (docs/controllers.md).
#include <cmath>

#include "shared/control/diff_drive.hpp"

namespace inspect::control {

struct AuxiliaryGains {
  double a1 = -1.0;
  double a2 = -1.2;
  double a3 = -0.5;
};

/// The reference at one instant: pose and feed-forward velocities.
struct ReferenceState {
  Pose2 pose;
  double v_m_s = 0.0;
  double w_rad_s = 0.0;
};

/// Eq 10: tracking error in the robot frame, actual - reference.
struct TrackingError {
  double x_m = 0.0;      // along the robot's heading (> 0: ahead of the reference)
  double y_m = 0.0;      // to the robot's left (> 0: left of the reference)
  double theta_rad = 0.0;
  double position_m() const { return std::hypot(x_m, y_m); }
};

/// Eq 10.
inline TrackingError trackingError(const Pose2& robot, const Pose2& ref) {
  const double dx = robot.x_m - ref.x_m, dy = robot.y_m - ref.y_m;
  const double c = std::cos(robot.theta_rad), s = std::sin(robot.theta_rad);
  return {c * dx + s * dy, -s * dx + c * dy, wrapAngle(robot.theta_rad - ref.theta_rad)};
}

/// Eq 12 (reading above).
inline Twist auxiliaryControl(const TrackingError& e, const ReferenceState& ref, const AuxiliaryGains& g) {
  return {ref.v_m_s * std::cos(e.theta_rad) + g.a1 * e.x_m,
          ref.w_rad_s + g.a2 * ref.v_m_s * std::sin(e.theta_rad) + g.a3 * e.y_m};
}

}  // namespace inspect::control
