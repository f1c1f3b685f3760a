#include "shared/perception/camera_geometry.hpp"

#include <cmath>

namespace inspect::perception {

namespace {

// The ray through picture point (u, v) in the pan frame (X ahead, Y left, Z up):
// the camera's axis is tilted up by `tilt` (pitch), a = left, b = up in the
// picture plane at unit distance.
struct Ray {
  double x, y, z;
};
Ray rayThrough(double u, double v, const CameraPose& cam) {
  const double f = cam.focalPx();
  const double a = (cam.width / 2.0 - u) / f, b = (cam.height / 2.0 - v) / f;
  const double tilt = cam.tilt_rad + cam.mount.tilt_deg * 3.14159265358979323846 / 180.0;
  const double ct = std::cos(tilt), st = std::sin(tilt);
  return {ct - b * st, a, st + b * ct};
}

}  // namespace

double CameraPose::focalPx() const {
  constexpr double kPi = 3.14159265358979323846;
  return (width / 2.0) / std::tan(mount.hfov_deg * kPi / 360.0);
}

double standingHeightM(double foot_row, double head_row, const CameraPose& cam) {
  const double u = cam.width / 2.0;
  const Ray foot = rayThrough(u, foot_row, cam);
  if (!(foot.z < -1e-9)) return std::nan("");
  const double t = cam.mount.z_m / -foot.z;
  const double d = t * std::hypot(foot.x, foot.y);  // along the floor to the feet
  const Ray head = rayThrough(u, head_row, cam);
  const double hd = std::hypot(head.x, head.y);
  if (!(hd > 1e-9)) return std::nan("");
  return cam.mount.z_m + d * head.z / hd;
}

Sighting sightingOf(const cv::Rect& box, const CameraPose& cam, int edge_px, double max_range_m) {
  Sighting s;
  const double u = box.x + box.width / 2.0;
  const Ray mid = rayThrough(u, box.y + box.height / 2.0, cam);
  const double in_pan = std::atan2(mid.y, mid.x);
  // The lens on the robot: the mount's offset (the pan axis; the lens is on it).
  const double cp = std::cos(cam.pan_rad), sp = std::sin(cam.pan_rad);
  s.bearing_rad = std::remainder(in_pan + cam.pan_rad, 2 * 3.14159265358979323846);
  const int bottom = box.y + box.height;
  if (bottom > cam.height - edge_px) return s;  // the feet may be cut off
  const Ray foot = rayThrough(u, bottom, cam);
  if (!(foot.z < -1e-9)) return s;  // at or above the horizon: never meets the floor
  const double t = cam.mount.z_m / -foot.z;
  const double fx = t * foot.x, fy = t * foot.y;  // pan frame, from the lens
  const double range = std::hypot(fx, fy);
  if (!(range <= max_range_m)) return s;
  s.range_m = range;
  s.x_m = cam.mount.x_m + cp * fx - sp * fy;
  s.y_m = cam.mount.y_m + sp * fx + cp * fy;
  return s;
}

}  // namespace inspect::perception
