#include "sim/detector_model.hpp"

#include <algorithm>
#include <cmath>

namespace inspect::sim {
namespace {
constexpr int kRays = 7;

double recallOf(const std::array<double, 6>& upto, const std::array<double, 6>& recall, double d) {
  for (std::size_t i = 0; i < upto.size(); ++i)
    if (d <= upto[i]) return recall[i];
  return 0.0;
}

/// Distance along a ray from (ox, oy) at `yaw` to a disc, or < 0 when it misses.
double rayDisc(double ox, double oy, double yaw, const PersonDisc& p) {
  const double dx = std::cos(yaw), dy = std::sin(yaw);
  const double fx = ox - p.x_m, fy = oy - p.y_m;
  const double b = fx * dx + fy * dy, c = fx * fx + fy * fy - p.radius_m * p.radius_m, disc = b * b - c;
  if (disc < 0) return -1.0;
  const double t = -b - std::sqrt(disc);
  return t > 0 ? t : -1.0;
}
}  // namespace

double visibleShare(const world::World& w, const control::Pose2& lens, double half_fov_rad, const PersonDisc& p,
                    const std::vector<PersonDisc>& others) {
  const double dx = p.x_m - lens.x_m, dy = p.y_m - lens.y_m, d = std::hypot(dx, dy);
  if (d <= p.radius_m) return 0.0;
  const double centre = std::atan2(dy, dx), half_width = std::asin(std::min(1.0, p.radius_m / d));
  int seen = 0;
  for (int k = 0; k < kRays; ++k) {
    const double yaw = centre + half_width * (2.0 * k / (kRays - 1) - 1.0) * 0.9;
    if (std::abs(std::remainder(yaw - lens.theta_rad, 2 * M_PI)) > half_fov_rad) continue;  // out of the picture
    const double reach = d - p.radius_m;
    if (const auto hit = world::castRay(w, {lens.x_m, lens.y_m}, yaw, reach); hit && *hit < reach) continue;
    bool hidden = false;
    for (const auto& o : others) {
      if (&o == &p) continue;
      const double t = rayDisc(lens.x_m, lens.y_m, yaw, o);
      hidden = hidden || (t > 0 && t < reach);
    }
    if (!hidden) ++seen;
  }
  return static_cast<double>(seen) / kRays;
}

behavior::CameraLook detectPeople(const world::World& w, const control::Pose2& robot, const config::CameraMount& mount,
                                  double pan_rad, const std::vector<PersonDisc>& people,
                                  const DetectorModelParams& params, std::mt19937_64& rng) {
  behavior::CameraLook look;
  look.lens_x_m = mount.x_m;
  look.lens_y_m = mount.y_m;
  look.axis_rad = pan_rad;
  look.half_fov_rad = mount.hfov_deg * M_PI / 360.0;
  const control::Pose2 at = config::mountPose(robot, {mount.x_m, mount.y_m, 0.0});
  const control::Pose2 lens{at.x_m, at.y_m, robot.theta_rad + pan_rad};
  // The picture's lower edge (4:3): the feet are in it beyond this distance.
  const double half_v = std::atan(std::tan(look.half_fov_rad) * 0.75);
  const double lower_edge = half_v - mount.tilt_deg * M_PI / 180.0;  // below the horizon
  const double feet_from_m = lower_edge > 0.01 ? mount.z_m / std::tan(lower_edge) : 1e9;
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::normal_distribution<double> n01(0.0, 1.0);
  const double sb = params.bearing_sigma_deg * M_PI / 180.0;
  for (const auto& p : people) {
    const double share = visibleShare(w, lens, look.half_fov_rad, p, people);
    if (share < 0.3) continue;
    const double d = std::hypot(p.x_m - lens.x_m, p.y_m - lens.y_m);
    const double recall = share >= 0.9 ? recallOf(params.upto_m, params.recall_clear, d)
                                       : recallOf(params.upto_m, params.recall_part, d);
    if (u01(rng) >= recall) continue;
    const double bearing = std::remainder(std::atan2(p.y_m - lens.y_m, p.x_m - lens.x_m) - robot.theta_rad, 2 * M_PI);
    double range = -1.0;
    if (d >= feet_from_m) {
      const double z = n01(rng);
      range = d * (1.0 + params.range_median + z * (z < 0 ? params.range_sigma_short : params.range_sigma_long));
      range = std::max(range, 0.5);
    }
    look.add({bearing + sb * n01(rng), range});
  }
  // False boxes: Poisson, uniform over the view.
  std::poisson_distribution<int> falses(params.false_per_picture);
  for (int k = falses(rng); k > 0; --k) {
    const double b = pan_rad + (2.0 * u01(rng) - 1.0) * look.half_fov_rad;
    look.add({b, params.false_min_m + u01(rng) * (params.false_max_m - params.false_min_m)});
  }
  return look;
}

DetectorModelParams wideHeadModel() {
  DetectorModelParams p;
  p.upto_m = {1.0, 1.5, 2.0, 3.0, 4.0, 6.0};
  p.recall_clear = {0.08, 0.50, 0.80, 0.61, 0.11, 0.03};
  p.recall_part = {0.03, 0.05, 0.0, 0.32, 0.0, 0.0};
  p.bearing_sigma_deg = 0.55;  // a normal's sigma from p50 0.33 / 0.674 and p90 0.96 / 1.645
  // A two-piece normal about the median: (9.9 + 12.6) / 1.2816 short, (30.9 - 9.9) / 1.2816 long.
  p.range_median = 0.099;
  p.range_sigma_short = 0.175;
  p.range_sigma_long = 0.164;
  p.false_per_picture = 0.0;  // none in 300 pictures
  p.false_min_m = 1.0;
  p.false_max_m = 3.0;
  return p;
}

}  // namespace inspect::sim
