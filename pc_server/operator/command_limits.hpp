#pragma once
// What an operator may ask of a robot, whatever the front end: the one home
// of the limits the operator service and route files check.

namespace inspect::server {

/// Fastest cruise speed of a go-to, a track or a route, m/s.
inline constexpr double kMaxCommandSpeed_m_s = 1.0;
/// A cruise speed an operator may ask for: (0, kMaxCommandSpeed_m_s] (NaN is not).
inline bool commandSpeedOk(double v_m_s) { return v_m_s > 0.0 && v_m_s <= kMaxCommandSpeed_m_s; }

}  // namespace inspect::server
