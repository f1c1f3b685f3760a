#pragma once
// What an operator may ask of a robot, whatever the front end: the one home
// of the limits the operator service and route files check.

namespace inspect::server {

/// Fastest cruise speed of a go-to, a track or a route, m/s.
inline constexpr double kMaxCommandSpeed_m_s = 1.0;

}  // namespace inspect::server
