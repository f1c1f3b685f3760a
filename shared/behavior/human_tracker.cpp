#include "shared/behavior/human_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace inspect::behavior {
namespace {
double segmentDistance(const MapSegment& s, double x, double y) {
  const double dx = s.x1 - s.x0, dy = s.y1 - s.y0;
  const double l2 = dx * dx + dy * dy;
  double u = l2 > 0 ? ((x - s.x0) * dx + (y - s.y0) * dy) / l2 : 0.0;
  u = std::clamp(u, 0.0, 1.0);
  return std::hypot(x - (s.x0 + u * dx), y - (s.y0 + u * dy));
}
}  // namespace

HumanTracker::HumanTracker(const config::UltrasonicConfig& sonar, const HumanTrackerParams& params,
                           std::vector<MapSegment> map)
    : sonar_(sonar), p_(params), map_(std::move(map)),
      grid_(static_cast<std::size_t>(params.grid_size) * static_cast<std::size_t>(params.grid_size)) {
  tracks_.reserve(static_cast<std::size_t>(p_.max_tracks));
  grid_origin_x_ = grid_origin_y_ = -0.5 * p_.grid_size * p_.grid_cell_m;
}

bool HumanTracker::nearMap(double x, double y) const {
  for (const auto& s : map_)
    if (segmentDistance(s, x, y) < p_.map_margin_m) return true;
  return false;
}

HumanTracker::Cell* HumanTracker::cell(double x, double y) {
  const int i = static_cast<int>(std::floor((x - grid_origin_x_) / p_.grid_cell_m));
  const int j = static_cast<int>(std::floor((y - grid_origin_y_) / p_.grid_cell_m));
  if (i < 0 || j < 0 || i >= p_.grid_size || j >= p_.grid_size) return nullptr;
  return &grid_[static_cast<std::size_t>(j) * static_cast<std::size_t>(p_.grid_size) + static_cast<std::size_t>(i)];
}

void HumanTracker::predict(double dt) {
  Eigen::Matrix4d f = Eigen::Matrix4d::Identity();
  f(0, 2) = f(1, 3) = dt;
  // Discrete white-noise acceleration model.
  const double q = p_.process_accel_m_s2 * p_.process_accel_m_s2;
  Eigen::Matrix4d qm = Eigen::Matrix4d::Zero();
  const double dt2 = dt * dt, dt3 = dt2 * dt / 2, dt4 = dt2 * dt2 / 4;
  qm(0, 0) = qm(1, 1) = dt4 * q;
  qm(0, 2) = qm(2, 0) = qm(1, 3) = qm(3, 1) = dt3 * q;
  qm(2, 2) = qm(3, 3) = dt2 * q;
  for (auto& t : tracks_) {
    t.x = f * t.x;
    t.p = f * t.p * f.transpose() + qm;
  }
}

void HumanTracker::update(HumanTrack& t, const Eigen::Vector2d& z, const Eigen::Matrix2d& r, double t_s) {
  Eigen::Matrix<double, 2, 4> h = Eigen::Matrix<double, 2, 4>::Zero();
  h(0, 0) = h(1, 1) = 1.0;
  const Eigen::Vector2d y = z - h * t.x;
  const Eigen::Matrix2d s = h * t.p * h.transpose() + r;
  const Eigen::Matrix<double, 4, 2> k = t.p * h.transpose() * s.inverse();
  t.x += k * y;
  t.p = (Eigen::Matrix4d::Identity() - k * h) * t.p;
  t.last_seen_s = t_s;
  ++t.hits;
}

void HumanTracker::step(const control::Pose2& pose, const std::array<double, 4>& ranges_m, double t_s) {
  const double dt = have_time_ ? std::clamp(t_s - last_t_s_, 0.0, 0.5) : 0.0;
  have_time_ = true;
  last_t_s_ = t_s;
  if (dt > 0) predict(dt);
  const double c = std::cos(pose.theta_rad), s = std::sin(pose.theta_rad);
  for (std::size_t i = 0; i < 4; ++i) {
    const double r = ranges_m[i];
    if (!(r > 0) || !std::isfinite(r) || r >= sonar_.max_range_m) continue;
    ++counters_.echoes;
    const auto& m = sonar_.mounts[i];
    const double bx = pose.x_m + c * m.x_m - s * m.y_m, by = pose.y_m + s * m.x_m + c * m.y_m;
    const double yaw = pose.theta_rad + m.yaw_rad;
    const double px = bx + r * std::cos(yaw), py = by + r * std::sin(yaw);
    // An echo is explained by the map when any point of its range arc within
    // the cone touches known structure (a corridor's side walls reach the
    // front sensors through the cone's edges).
    bool explained = false;
    for (int k = -3; k <= 3 && !explained && !map_.empty(); ++k) {
      const double a = yaw + k * sonar_.beam_width_rad / 6.0;
      explained = nearMap(bx + r * std::cos(a), by + r * std::sin(a));
    }
    if (explained) {
      ++counters_.static_map;
      continue;
    }
    // Persistence: a person passes through a 0.2 m cell in well under a
    // second; structure keeps being hit in the same place for longer.
    if (Cell* ce = cell(px, py)) {
      const auto now = static_cast<float>(t_s);
      if (ce->last_s < 0 || now - ce->last_s > p_.grid_forget_s) ce->first_s = now;
      ce->last_s = now;
      if (now - ce->first_s > p_.grid_static_s) {
        ++counters_.static_grid;
        continue;
      }
    }
    // Measurement covariance: range noise along the beam, the cone's width across it.
    const double along = std::max(p_.range_sigma_m, 0.01);
    const double across = std::max(0.05, r * std::tan(sonar_.beam_width_rad / 2) / 2);
    Eigen::Matrix2d rot;
    rot << std::cos(yaw), -std::sin(yaw), std::sin(yaw), std::cos(yaw);
    const Eigen::Matrix2d rm = rot * Eigen::Vector2d(along * along, across * across).asDiagonal() * rot.transpose();
    const Eigen::Vector2d z(px, py);
    HumanTrack* best = nullptr;
    double best_d = p_.gate_m;
    for (auto& t : tracks_) {
      const double d = std::hypot(t.x[0] - px, t.x[1] - py);
      if (d < best_d) {
        best_d = d;
        best = &t;
      }
    }
    if (best) {
      update(*best, z, rm, t_s);
      ++counters_.associated;
    } else if (static_cast<int>(tracks_.size()) < p_.max_tracks) {
      HumanTrack t;
      t.id = next_id_++;
      t.x << px, py, 0, 0;
      t.p = Eigen::Matrix4d::Zero();
      t.p.block<2, 2>(0, 0) = rm;
      t.p(2, 2) = t.p(3, 3) = 1.0;  // unknown velocity: up to ~1-2 m/s
      t.first_seen_s = t.last_seen_s = t_s;
      t.hits = 1;
      tracks_.push_back(t);
      ++counters_.tracks_created;
    }
  }
  // Confirm, reclassify, drop.
  for (auto& t : tracks_) {
    if (!t.confirmed && t.hits >= p_.confirm_hits && t.last_seen_s - t.first_seen_s <= p_.confirm_window_s + 1e-9) {
      t.confirmed = true;
      ++counters_.tracks_confirmed;
    }
    if (t.speed() < p_.min_person_speed_m_s) {
      if (t.slow_since_s < 0) t.slow_since_s = t_s;
      t.moving_since_s = -1;
    } else {
      t.slow_since_s = -1;
      if (t.moving_since_s < 0) t.moving_since_s = t_s;
    }
    // Once a person, a short slow-down (a pause) keeps it one until static_after_s.
    if (t.confirmed && t.moving_since_s >= 0 && t_s - t.moving_since_s >= p_.moving_for_s) t.person = true;
  }
  std::erase_if(tracks_, [&](const HumanTrack& t) {
    if (t_s - t.last_seen_s > p_.coast_s) {
      if (!t.confirmed) ++counters_.tracks_unconfirmed_dropped;
      return true;
    }
    if (!t.confirmed && t_s - t.first_seen_s > p_.confirm_window_s && t.hits < p_.confirm_hits) {
      ++counters_.tracks_unconfirmed_dropped;
      return true;
    }
    if (t.slow_since_s >= 0 && t_s - t.slow_since_s > p_.static_after_s) {
      ++counters_.tracks_static_dropped;
      return true;
    }
    return false;
  });
}

const HumanTrack* HumanTracker::nearest(const control::Pose2& pose) const {
  const HumanTrack* best = nullptr;
  double bd = std::numeric_limits<double>::infinity();
  for (const auto& t : tracks_) {
    if (!t.isPerson()) continue;
    const double d = std::hypot(t.x[0] - pose.x_m, t.x[1] - pose.y_m);
    if (d < bd) {
      bd = d;
      best = &t;
    }
  }
  return best;
}

}  // namespace inspect::behavior
