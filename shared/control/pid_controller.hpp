#pragma once
// PID controller (paper Eq 14): u = kp e + ki * integral(e) + kd de/dt.
// Pure: the state is passed in, dt is an argument, no clock is read.
// - the integral accumulates ki * e * dt, so gains may change every step
//   (fuzzy gain scheduling, Eq 15) without a bump in the output;
// - the derivative acts on the measurement (no kick on set-point steps),
//   through a first-order filter (at 100 Hz an unfiltered kd of the paper's
//   size destabilises a hub-motor loop; docs/controllers.md);
// - anti-windup: the integral is clamped, and it stops integrating while the
//   output is saturated in the direction the error pushes;
// - non-finite inputs or dt <= 0 hold the previous output and leave the state untouched.
#include <algorithm>
#include <cmath>

namespace inspect::control {

struct PidGains {
  double kp = 0.0;
  double ki = 0.0;
  double kd = 0.0;
};

struct PidConfig {
  double derivative_filter_s = 0.1;  // first-order filter time constant on the derivative
  double integral_limit = 10.0;      // |integral term| bound, output units
  double output_min = -1e9;
  double output_max = 1e9;
};

struct PidState {
  double integral = 0.0;     // the integral TERM (already multiplied by ki), output units
  double derivative = 0.0;   // filtered kd * d(measurement)/dt
  double prev_measurement = 0.0;
  bool primed = false;       // prev_measurement valid
  double output = 0.0;       // last output
  bool saturated = false;    // last output was clipped
};

/// One PID step; returns the new output (also kept in state.output).
inline double pidStep(const PidConfig& cfg, const PidGains& g, PidState& s, double setpoint, double measurement,
                      double dt_s) {
  if (!std::isfinite(setpoint) || !std::isfinite(measurement) || !std::isfinite(dt_s) || dt_s <= 0.0 ||
      !std::isfinite(g.kp) || !std::isfinite(g.ki) || !std::isfinite(g.kd))
    return s.output;
  const double e = setpoint - measurement;
  // Derivative on measurement, filtered (backward Euler of Tf y' + y = kd dm/dt).
  const double dm = s.primed ? (measurement - s.prev_measurement) : 0.0;
  const double tf = cfg.derivative_filter_s;
  s.derivative = (tf * s.derivative + g.kd * dm) / (tf + dt_s);
  s.prev_measurement = measurement;
  s.primed = true;
  // Conditional integration (clamping): the step's integral increment is kept
  // only if it does not drive the output further into saturation.
  const double di = g.ki * e * dt_s;
  const double p_d = g.kp * e - s.derivative;
  const double tentative = std::clamp(s.integral + di, -cfg.integral_limit, cfg.integral_limit);
  const double u_try = p_d + tentative;
  const bool deepen = (u_try > cfg.output_max && di > 0) || (u_try < cfg.output_min && di < 0);
  if (!deepen) s.integral = tentative;
  const double u = p_d + s.integral;  // Eq 14
  s.output = std::clamp(u, cfg.output_min, cfg.output_max);
  s.saturated = s.output != u;
  return s.output;
}

}  // namespace inspect::control
