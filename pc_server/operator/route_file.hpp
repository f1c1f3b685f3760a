#pragma once
// Route files for the operator's `route <file>` and `inspect <route>`
// (config/routes/*.yaml): a name, an optional cruise speed, the site map the
// points refer to, and the points in the robot's odometry frame - either as a
// flat `waypoints_m` list or as `points` with inspection dwell times, camera
// presets and labels (docs/console.md, docs/gas.md).
#include <optional>
#include <string>
#include <vector>

#include "inspect_robot/v1/link.pb.h"
#include "pc_server/operator/command_limits.hpp"
#include "shared/control/wheel_profile.hpp"

namespace inspect::server {

/// One point of a route.
struct RoutePoint {
  double x_m = 0.0;
  double y_m = 0.0;
  double dwell_s = 0.0;             // > 0: an inspection point (stop this long)
  std::optional<v1::Ptz> ptz;       // camera preset applied on arrival
  std::string label;
};

/// A route as read from its file.
struct Route {
  std::string name;
  std::string file;                 // the file it was read from
  double speed_m_s = 0.0;           // 0 = the robot's default
  std::string map;                  // world file of the site (resolved path; "" = none)
  std::vector<RoutePoint> points;
  /// A wheel test instead of points (`wheel_test:`): open-loop steps and chirps
  /// for plant identification (docs/tuning.md).
  std::vector<control::WheelProfileSegment> wheel_test;
  bool isWheelTest() const { return !wheel_test.empty(); }
  /// x0, y0, x1, y1, ... (the points' coordinates)
  std::vector<double> waypointsM() const;
  /// Points with a dwell time.
  int inspectionPoints() const;
};

/// Most waypoints a route may have (the robot accepts as many goals per command).
inline constexpr int kMaxRoutePoints = 100;
/// Longest dwell at one point, s.
inline constexpr double kMaxDwell_s = 3600.0;

/// Reads and checks a route file; throws config::ConfigError naming the file and key
/// (unknown keys, an odd or empty waypoint list, non-finite or out-of-range values,
/// a map file that does not exist).
Route loadRouteFile(const std::string& path);
/// The same from YAML text (`name` stands in for the file in messages).
Route loadRouteText(const std::string& yaml, const std::string& name);
/// `inspect`'s argument: a file path, or a name looked up as config/routes/<name>.yaml
/// (relative to the working directory). Returns the path; throws config::ConfigError when none exists.
std::string resolveRoute(const std::string& name_or_path);
/// The route an operator names (`route`, `inspect`, the Foxglove /route and
/// /inspect): a path (with a '/' or ending in .yaml) is read as given, with
/// its own errors; a bare name is looked up as resolveRoute does. Throws config::ConfigError.
Route openRoute(const std::string& name_or_path);
/// The operator's line about a route about to be sent: "route 'lab_loop': 5
/// points at 0.3 m/s", "inspection 'gas_lab': 9 points, 4 inspection points,
/// map ...", "wheel test 'identification': 12 segments, 40.0 s of ...".
std::string routeSummary(const Route& r, bool inspection);

/// The WheelTest command body of a wheel-test route.
v1::WheelTest wheelTestOf(const Route& r);

/// The GoTo command body of a route (inspection: the gas reaction and dwell apply).
v1::GoTo goToOf(const Route& r, bool inspection = false);

}  // namespace inspect::server
