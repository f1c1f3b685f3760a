#include "pc_server/recording/run_stats.hpp"

#include <algorithm>
#include <cmath>

namespace inspect::server {

void RunStats::add(const v1::Telemetry& t) {
  ++f_.telemetry;
  if (f_.telemetry == 1) first_us_ = t.robot_time_us();
  last_us_ = std::max(last_us_, t.robot_time_us());
  const double x = t.pose().x_m(), y = t.pose().y_m();
  if (have_pose_) {
    const double step = std::hypot(x - last_x_, y - last_y_);
    if (step < kMaxOdometryStepM) f_.distance_m += step;
  }
  have_pose_ = true;
  last_x_ = x;
  last_y_ = y;
  // Fields the robot left out (unknown, link protocol 2) count as no sample.
  if (t.has_nearest_person_m() && t.nearest_person_m() >= 0 &&
      (f_.min_person_m < 0 || t.nearest_person_m() < f_.min_person_m))
    f_.min_person_m = t.nearest_person_m();
  if (t.mode() == v1::TRACKING && t.has_position_error_m()) {
    ++f_.tracking_samples;
    f_.max_position_error_m = std::max(f_.max_position_error_m, t.position_error_m());
    if (t.has_angle_error_rad()) f_.max_angle_error_rad = std::max(f_.max_angle_error_rad, t.angle_error_rad());
    sq_sum_ += t.position_error_m() * t.position_error_m();
  }
  if (f_.gas.size() < static_cast<std::size_t>(t.gas_size())) {
    for (int c = static_cast<int>(f_.gas.size()); c < t.gas_size(); ++c) f_.gas.push_back({c, 0, 0, 0});
    gas_sum_.resize(f_.gas.size(), 0.0);
  }
  for (int c = 0; c < t.gas_size(); ++c) {
    if (std::isnan(t.gas(c))) continue;  // no data from that sensor
    auto& g = f_.gas[static_cast<std::size_t>(c)];
    g.max = g.samples ? std::max(g.max, t.gas(c)) : t.gas(c);
    ++g.samples;
    gas_sum_[static_cast<std::size_t>(c)] += t.gas(c);
  }
}

RunFigures RunStats::figures() const {
  RunFigures f = f_;
  f.duration_s = static_cast<double>(last_us_ - first_us_) * 1e-6;
  f.rms_position_error_m = f_.tracking_samples ? std::sqrt(sq_sum_ / static_cast<double>(f_.tracking_samples)) : 0;
  for (std::size_t c = 0; c < f.gas.size(); ++c)
    if (f.gas[c].samples) f.gas[c].mean = gas_sum_[c] / static_cast<double>(f.gas[c].samples);
  return f;
}

}  // namespace inspect::server
