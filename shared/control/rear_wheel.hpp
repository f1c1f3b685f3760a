#pragma once
// Turning geometry of the paper's robot (Eqs 4-6): the turning radius of the
// axle midpoint and the angle beta of the servo-steered rear wheel as
// functions of the wheel speed ratio k = w_outer / w_inner.
// In the project's convention (docs/conventions.md) a left turn has the right
// wheel outer; beta > 0 steers for a left turn. Straight ahead: k = 1, beta = 0.
#include <cmath>
#include <limits>

namespace inspect::control {

/// The paper's lengths (Fig 2): L, L1, L2, L3 in metres.
struct RearWheelGeometry {
  double track_m = 0.438;
  double l1_m = 0.214;
  double l2_m = 0.172;
  double l3_m = 0.046;
};

/// Eq 4: radius of the axle midpoint's circle for a speed ratio k (|k| != 1).
/// k = -1 (wheels opposite) gives 0 (turning in place); k = 1 gives +infinity.
inline double turningRadiusFromRatio(double k, double track_m) {
  if (k == 1.0) return std::numeric_limits<double>::infinity();
  return (1.0 + k) * track_m / (2.0 * (k - 1.0));
}

/// Inverse of Eq 4: speed ratio k for a turning radius R >= 0.
inline double ratioFromTurningRadius(double r_m, double track_m) {
  if (std::isinf(r_m)) return 1.0;
  return (2.0 * r_m + track_m) / (2.0 * r_m - track_m);
}

/// Eq 5: speed ratio k for a rear wheel angle beta (rad, |beta| < pi/2).
inline double ratioFromRearAngle(double beta_rad, const RearWheelGeometry& g) {
  const double a = g.l1_m + g.l2_m + g.l3_m / std::cos(beta_rad);
  const double lt = g.track_m * std::tan(beta_rad);
  return (2.0 * a + lt) / (2.0 * a - lt);
}

/// Eq 6 solved for beta: tan(beta) = (L1 + L2 + L3 / cos(beta)) / R, with R
/// from Eq 4. Solved by bisection on beta in [0, pi/2) for the magnitude
/// (the right side grows slower than tan), sign taken from the turn direction.
/// Returns NaN for a non-finite ratio.
inline double rearAngleFromRatio(double k, const RearWheelGeometry& g) {
  if (!std::isfinite(k)) return std::nan("");
  if (k == 1.0) return 0.0;
  const double r = turningRadiusFromRatio(k, g.track_m);
  const double sign = r >= 0.0 ? 1.0 : -1.0;
  const double ar = std::abs(r);
  // f(beta) = tan(beta) * R - (L1 + L2 + L3 / cos(beta)) is increasing on [0, pi/2).
  auto f = [&](double b) { return std::tan(b) * ar - (g.l1_m + g.l2_m + g.l3_m / std::cos(b)); };
  double lo = 0.0, hi = 1.5707963267948966 - 1e-9;
  if (f(lo) >= 0.0) return 0.0;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (f(mid) < 0.0 ? lo : hi) = mid;
  }
  return sign * 0.5 * (lo + hi);
}

}  // namespace inspect::control
