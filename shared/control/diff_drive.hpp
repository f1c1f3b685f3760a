#pragma once
// Differential-drive kinematics (paper Eqs 1-3, 13) in the project's single
// convention: x forward, y left, yaw counter-clockwise positive, wheel 1 = left,
// wheel 2 = right, so a faster RIGHT wheel turns the robot left:
//   v = r (w_l + w_r) / 2,  w = r (w_r - w_l) / L.
// (The paper writes th' = r/L (w1 - w2); see docs/conventions.md.)
#include <cmath>
#include <numbers>

namespace inspect::control {

/// Wheel angular speeds of the two driving wheels, rad/s.
struct WheelSpeeds {
  double left_rad_s = 0.0;
  double right_rad_s = 0.0;
};

/// Unicycle velocities of the axle midpoint.
struct Twist {
  double v_m_s = 0.0;
  double w_rad_s = 0.0;
};

/// Planar pose, yaw wrapped to [-pi, pi].
struct Pose2 {
  double x_m = 0.0;
  double y_m = 0.0;
  double theta_rad = 0.0;
};

/// Wraps an angle to [-pi, pi].
inline double wrapAngle(double a) {
  if (!std::isfinite(a)) return 0.0;
  a = std::remainder(a, 2.0 * std::numbers::pi);
  return a;
}

/// Eq 13 (our convention): wheel speeds for a unicycle twist.
inline WheelSpeeds wheelsFromTwist(const Twist& t, double wheel_radius_m, double track_m) {
  return {(t.v_m_s - t.w_rad_s * track_m / 2.0) / wheel_radius_m, (t.v_m_s + t.w_rad_s * track_m / 2.0) / wheel_radius_m};
}

/// Eqs 1-3 (our convention): unicycle twist from wheel speeds.
inline Twist twistFromWheels(const WheelSpeeds& w, double wheel_radius_m, double track_m) {
  return {wheel_radius_m * (w.left_rad_s + w.right_rad_s) / 2.0, wheel_radius_m * (w.right_rad_s - w.left_rad_s) / track_m};
}

/// Scales a twist so neither wheel exceeds max_wheel_rad_s, keeping the turning radius.
inline Twist limitTwist(const Twist& t, double wheel_radius_m, double track_m, double max_wheel_rad_s) {
  const WheelSpeeds w = wheelsFromTwist(t, wheel_radius_m, track_m);
  const double m = std::max(std::abs(w.left_rad_s), std::abs(w.right_rad_s));
  if (m <= max_wheel_rad_s || m <= 0.0) return t;
  const double k = max_wheel_rad_s / m;
  return {t.v_m_s * k, t.w_rad_s * k};
}

/// Dead-reckoning step from wheel travel (midpoint integration).
inline Pose2 integrateOdometry(const Pose2& p, double d_left_m, double d_right_m, double track_m) {
  const double ds = (d_left_m + d_right_m) / 2.0;
  const double dth = (d_right_m - d_left_m) / track_m;
  const double mid = p.theta_rad + dth / 2.0;
  return {p.x_m + ds * std::cos(mid), p.y_m + ds * std::sin(mid), wrapAngle(p.theta_rad + dth)};
}

}  // namespace inspect::control

namespace inspect::control {

/// Dead-reckoning step as the robot runs it: position from the wheels'
/// travel along the mean of the old and new heading, heading from the
/// heading sensor (paper: +-0.002 rad, better than wheel-derived yaw).
inline Pose2 odometryWithHeading(const Pose2& p, double d_left_m, double d_right_m, double heading_rad) {
  const double th = wrapAngle(heading_rad);
  const double mid = p.theta_rad + wrapAngle(th - p.theta_rad) / 2.0;
  const double ds = (d_left_m + d_right_m) / 2.0;
  return {p.x_m + ds * std::cos(mid), p.y_m + ds * std::sin(mid), th};
}

}  // namespace inspect::control
