#pragma once
// Route files for the console's `route <file>` (config/routes/*.yaml): a name,
// an optional cruise speed and the waypoints in the robot's odometry frame.
#include <string>
#include <vector>

#include "inspect/v1/link.pb.h"

namespace inspect::server {

/// A route as read from its file.
struct Route {
  std::string name;
  double speed_m_s = 0.0;  // 0 = the robot's default
  std::vector<double> waypoints_m;  // x0, y0, x1, y1, ...
};

/// Most waypoints a route may have (the robot accepts as many goals per command).
inline constexpr int kMaxRoutePoints = 100;
/// Fastest cruise speed a route may ask for, m/s.
inline constexpr double kMaxRouteSpeed_m_s = 1.0;

/// Reads and checks a route file; throws config::ConfigError naming the file and key
/// (unknown keys, an odd or empty waypoint list, non-finite or out-of-range values).
Route loadRouteFile(const std::string& path);
/// The same from YAML text (`name` stands in for the file in messages).
Route loadRouteText(const std::string& yaml, const std::string& name);

/// The GoTo command body of a route.
v1::GoTo goToOf(const Route& r);

}  // namespace inspect::server
