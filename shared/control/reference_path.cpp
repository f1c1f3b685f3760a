#include "shared/control/reference_path.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "shared/control/tracking_controller.hpp"

namespace inspect::control {
namespace {

class CirclePath final : public ReferencePath {
 public:
  CirclePath(const Pose2& start, double radius_m, double speed_m_s, double laps)
      : start_(start), r_(radius_m), v_(speed_m_s), laps_(laps) {
    // Centre to the left of the start heading for r > 0 (counter-clockwise).
    cx_ = start.x_m - r_ * std::sin(start.theta_rad);
    cy_ = start.y_m + r_ * std::cos(start.theta_rad);
  }
  double length_m() const override { return 2.0 * std::numbers::pi * std::abs(r_) * laps_; }
  PathSample at(double s) const override {
    s = std::clamp(s, 0.0, length_m());
    const double phi = s / r_;  // heading change, signed
    const double th = start_.theta_rad + phi;
    return {{cx_ + r_ * std::sin(th), cy_ - r_ * std::cos(th), wrapAngle(th)}, 1.0 / r_, v_};
  }
  std::string describe() const override {
    std::ostringstream os;
    os << "circle r=" << r_ << " m v=" << v_ << " m/s laps=" << laps_;
    return os.str();
  }

 private:
  Pose2 start_;
  double r_, v_, laps_, cx_ = 0, cy_ = 0;
};

class LinePath final : public ReferencePath {
 public:
  LinePath(const Pose2& start, double length_m, double speed_m_s) : start_(start), len_(length_m), v_(speed_m_s) {}
  double length_m() const override { return len_; }
  PathSample at(double s) const override {
    s = std::clamp(s, 0.0, len_);
    return {{start_.x_m + s * std::cos(start_.theta_rad), start_.y_m + s * std::sin(start_.theta_rad),
             start_.theta_rad},
            0.0,
            v_};
  }
  std::string describe() const override {
    std::ostringstream os;
    os << "line length=" << len_ << " m v=" << v_ << " m/s";
    return os.str();
  }

 private:
  Pose2 start_;
  double len_, v_;
};

class WaypointPath final : public ReferencePath {
 public:
  explicit WaypointPath(const std::vector<TimedWaypoint>& w) : wps_(w) {
    if (w.size() < 2) throw std::invalid_argument("a waypoint path needs at least 2 waypoints");
    cum_.push_back(0.0);
    for (std::size_t i = 1; i < w.size(); ++i) {
      const double dt = w[i].t_s - w[i - 1].t_s;
      if (!(dt > 0)) throw std::invalid_argument("waypoint times must increase (waypoint " + std::to_string(i) + ")");
      const double d = std::hypot(w[i].x_m - w[i - 1].x_m, w[i].y_m - w[i - 1].y_m);
      if (!(d > 1e-9)) throw std::invalid_argument("waypoint " + std::to_string(i) + " repeats the previous one");
      cum_.push_back(cum_.back() + d);
      speed_.push_back(d / dt);
    }
  }
  double length_m() const override { return cum_.back(); }
  PathSample at(double s) const override {
    s = std::clamp(s, 0.0, length_m());
    std::size_t i = static_cast<std::size_t>(std::upper_bound(cum_.begin(), cum_.end(), s) - cum_.begin());
    i = std::clamp<std::size_t>(i, 1, wps_.size() - 1);
    const auto& a = wps_[i - 1];
    const auto& b = wps_[i];
    const double seg = cum_[i] - cum_[i - 1];
    const double f = (s - cum_[i - 1]) / seg;
    return {{a.x_m + f * (b.x_m - a.x_m), a.y_m + f * (b.y_m - a.y_m), std::atan2(b.y_m - a.y_m, b.x_m - a.x_m)},
            0.0,
            speed_[i - 1]};
  }
  std::string describe() const override {
    std::ostringstream os;
    os << "waypoints n=" << wps_.size() << " length=" << length_m() << " m";
    return os.str();
  }

 private:
  std::vector<TimedWaypoint> wps_;
  std::vector<double> cum_;
  std::vector<double> speed_;
};

}  // namespace

std::unique_ptr<ReferencePath> makeCircle(const Pose2& start, double radius_m, double speed_m_s, double laps) {
  if (!(std::abs(radius_m) > 1e-3) || !std::isfinite(radius_m)) throw std::invalid_argument("circle radius must be non-zero");
  if (!(speed_m_s > 0) || !std::isfinite(speed_m_s)) throw std::invalid_argument("speed must be positive");
  if (!(laps > 0)) throw std::invalid_argument("laps must be positive");
  return std::make_unique<CirclePath>(start, radius_m, speed_m_s, laps);
}

std::unique_ptr<ReferencePath> makeLine(const Pose2& start, double length_m, double speed_m_s) {
  if (!(length_m > 0) || !std::isfinite(length_m)) throw std::invalid_argument("line length must be positive");
  if (!(speed_m_s > 0) || !std::isfinite(speed_m_s)) throw std::invalid_argument("speed must be positive");
  return std::make_unique<LinePath>(start, length_m, speed_m_s);
}

std::unique_ptr<ReferencePath> makeTimedWaypoints(const std::vector<TimedWaypoint>& wps) {
  return std::make_unique<WaypointPath>(wps);
}

std::unique_ptr<ReferencePath> makeRectangleWaypoints(double length_m, double speed_m_s) {
  if (!(length_m > 0) || !std::isfinite(length_m)) throw std::invalid_argument("rectangle length must be positive");
  if (!(speed_m_s > 0) || !std::isfinite(speed_m_s)) throw std::invalid_argument("speed must be positive");
  const double a = length_m, b = length_m / 2.0;
  const double corners[5][2] = {{0, 0}, {a, 0}, {a, b}, {0, b}, {0, 0}};
  std::vector<TimedWaypoint> wps;
  double t = 0;
  for (int k = 0; k < 5; ++k) {
    if (k) t += std::hypot(corners[k][0] - corners[k - 1][0], corners[k][1] - corners[k - 1][1]) / speed_m_s;
    wps.push_back({t, corners[k][0], corners[k][1]});
  }
  return makeTimedWaypoints(wps);
}

ReferenceState advance(const ReferencePath& path, PathProgress& p, double speed_factor, double dt_s) {
  const double f = std::isfinite(speed_factor) ? std::clamp(speed_factor, 0.0, 1.0) : 0.0;
  const PathSample here = path.at(p.s_m);
  if (!p.done && dt_s > 0) {
    p.s_m += here.speed_m_s * f * dt_s;
    p.t_s += dt_s;
    if (p.s_m >= path.length_m()) {
      p.s_m = path.length_m();
      p.done = true;
    }
  }
  const PathSample now = path.at(p.s_m);
  const double v = p.done ? 0.0 : now.speed_m_s * f;
  return {now.pose, v, v * now.curvature_1_m};
}

}  // namespace inspect::control
