#pragma once
// What a person's box in a camera picture says on the floor: the bearing of
// the box's centre column in the robot frame, and - when the feet are in the
// picture - the range from its bottom row on a flat floor (docs/human-
// awareness.md, "Detection on the robot"). A pinhole camera with square
// pixels (focal length from the picture's width and the horizontal field of
// view) on the PTZ head: pan about the vertical (counter-clockwise positive),
// then tilt (up positive), the lens at the mount's position and height.
// Pure functions.
#include <optional>

#include <opencv2/core.hpp>

#include "shared/config/robot_config.hpp"

namespace inspect::perception {

/// The camera of one picture: its size, the mount and the PTZ angles it was
/// taken at.
struct CameraPose {
  int width = 640, height = 480;
  config::CameraMount mount;
  double pan_rad = 0.0;   // PTZ pan, counter-clockwise positive (0 = straight ahead)
  double tilt_rad = 0.0;  // PTZ tilt, up positive; the mount's own tilt_deg adds to it
  double focalPx() const;
};

/// One person seen, in the robot frame (x ahead of the axle midpoint, y left).
struct Sighting {
  double bearing_rad = 0.0;       // from the lens, robot frame, counter-clockwise from ahead
  std::optional<double> range_m;  // lens to the feet along the floor; none when the feet are not in view
  double x_m = 0.0, y_m = 0.0;    // the feet, robot frame (meaningful when range_m is set)
};

/// The sighting of a box: the bearing of its centre column at the row of
/// its middle, the range from its bottom row when that row is inside the
/// picture (at least `edge_px` above its bottom edge) and the ray through it
/// meets the floor within `max_range_m`.
Sighting sightingOf(const cv::Rect& box, const CameraPose& cam, int edge_px = 2, double max_range_m = 30.0);

/// How tall someone standing on the floor is whose feet are at picture row
/// `foot_row` and the top of whose head is at `head_row` (on the picture's
/// centre column); NaN when the foot row is at or above the horizon (no
/// floor there). The detector's floor band (people_detector.hpp) uses it.
double standingHeightM(double foot_row, double head_row, const CameraPose& cam);

}  // namespace inspect::perception
