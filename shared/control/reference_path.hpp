#pragma once
// Reference paths for trajectory tracking: circle, straight line, timed
// waypoints. A path is parametrised by arc length s; each point carries the
// nominal speed there, so the tracker can advance s by v * speed_factor * dt
// (the fuzzy speed strategy slows the robot ON its path, as in the paper).
#include <memory>
#include <string>
#include <vector>

#include "shared/control/diff_drive.hpp"

namespace inspect::control {

/// One point of a path.
struct PathSample {
  Pose2 pose;
  double curvature_1_m = 0.0;  // d(theta)/ds, > 0 turning left
  double speed_m_s = 0.0;      // nominal speed at this point
};

class ReferencePath {
 public:
  virtual ~ReferencePath() = default;
  /// Total arc length, m.
  virtual double length_m() const = 0;
  /// The sample at arc length s (clamped to [0, length]).
  virtual PathSample at(double s_m) const = 0;
  /// Short description for logs and telemetry, e.g. "circle r=3.5 m v=0.5 m/s".
  virtual std::string describe() const = 0;
};

/// A circle through `start`, tangent to its heading; counter-clockwise for
/// radius > 0, clockwise for radius < 0. `laps` times round.
std::unique_ptr<ReferencePath> makeCircle(const Pose2& start, double radius_m, double speed_m_s, double laps = 1.0);
/// A straight line of `length_m` from `start` along its heading.
std::unique_ptr<ReferencePath> makeLine(const Pose2& start, double length_m, double speed_m_s);

/// A waypoint reached at a given time.
struct TimedWaypoint {
  double t_s = 0.0;
  double x_m = 0.0;
  double y_m = 0.0;
};
/// A polyline through timed waypoints (times strictly increasing); the speed
/// on each segment is its length over its duration. Throws std::invalid_argument.
std::unique_ptr<ReferencePath> makeTimedWaypoints(const std::vector<TimedWaypoint>& wps);
/// Waypoints of a length x length/2 rectangle from the origin, counter-clockwise,
/// corners timed at speed_m_s (the experiments' and the tuner's "waypoints").
std::unique_ptr<ReferencePath> makeRectangleWaypoints(double length_m, double speed_m_s);

/// Moves along a path: s advances by speed * factor * dt. Pure state + step.
struct PathProgress {
  double s_m = 0.0;
  double t_s = 0.0;
  bool done = false;
};

/// Advances `p` by dt with the speed factor (0..1) and returns the reference
/// to track now (pose, v = speed * factor, w = v * curvature).
struct ReferenceState;
ReferenceState advance(const ReferencePath& path, PathProgress& p, double speed_factor, double dt_s);

}  // namespace inspect::control
