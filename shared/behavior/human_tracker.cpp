#include "shared/behavior/human_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace inspect::behavior {
namespace {
Eigen::Matrix2d beamCovariance(double yaw, double along, double across) {
  Eigen::Matrix2d rot;
  rot << std::cos(yaw), -std::sin(yaw), std::sin(yaw), std::cos(yaw);
  return rot * Eigen::Vector2d(along * along, across * across).asDiagonal() * rot.transpose();
}
}  // namespace

HumanTracker::HumanTracker(const config::UltrasonicConfig& sonar, const HumanTrackerParams& params,
                           std::vector<geometry::Segment> map)
    : sonar_(sonar), p_(params), map_(std::move(map)),
      grid_(static_cast<std::size_t>(params.grid_size) * static_cast<std::size_t>(params.grid_size)) {
  tracks_.reserve(static_cast<std::size_t>(p_.max_tracks));
  grid_origin_x_ = grid_origin_y_ = -0.5 * p_.grid_size * p_.grid_cell_m;
}

std::optional<std::pair<Eigen::Vector2d, Eigen::Matrix2d>> HumanTracker::triangulate(const control::Pose2& pose,
                                                                                     double r0, double r1) const {
  const auto& m0 = sonar_.mounts[0];
  const auto& m1 = sonar_.mounts[1];
  if (std::abs(m0.yaw_rad - m1.yaw_rad) > 1e-6) return std::nullopt;  // not a parallel pair
  // Beam frame of the pair: u along the beams, w across (left positive).
  const double cy = std::cos(m0.yaw_rad), sy = std::sin(m0.yaw_rad);
  const double u0 = cy * m0.x_m + sy * m0.y_m, w0 = -sy * m0.x_m + cy * m0.y_m;
  const double u1 = cy * m1.x_m + sy * m1.y_m, w1 = -sy * m1.x_m + cy * m1.y_m;
  const double base = w1 - w0;
  if (std::abs(base) < 0.05 || std::abs(u0 - u1) > 0.02) return std::nullopt;
  if (std::abs(r0 - r1) >= std::abs(base)) return std::nullopt;  // no common point: two objects
  const double w = (r0 * r0 - r1 * r1 + w1 * w1 - w0 * w0) / (2 * base);
  const double du2 = r0 * r0 - (w - w0) * (w - w0);
  if (du2 <= 0) return std::nullopt;
  const double u = 0.5 * (u0 + u1) + std::sqrt(du2);
  const double half = sonar_.beam_width_rad / 2;
  const double uc = 0.5 * (u0 + u1);
  // Range noise can put the solution outside the cones: the object is in both,
  // so clamp it to their overlap at that distance.
  const double reach = (u - uc) * std::tan(half);
  const double lo = std::max(w0, w1) - reach, hi = std::min(w0, w1) + reach;
  if (lo > hi) return std::nullopt;  // the cones do not overlap yet at this distance
  const double wc = std::clamp(w, lo, hi);
  // Robot frame, then odometry frame.
  const double rx = cy * u - sy * wc, ry = sy * u + cy * wc;
  const control::Pose2 at = config::mountPose(pose, {rx, ry, 0.0});
  const Eigen::Vector2d z(at.x_m, at.y_m);
  // Lateral sigma from the two range errors (uniform +-range_sigma: sigma / sqrt 3),
  // never worse than a single cone.
  const double sr = std::max(p_.range_sigma_m, 0.01) / std::sqrt(3.0);
  const double mean_r = 0.5 * (r0 + r1);
  const double across = std::clamp(std::hypot(r0, r1) * sr / std::abs(base), 0.03,
                                   std::max(0.05, mean_r * std::tan(half) / 2));
  return std::make_pair(z, beamCovariance(pose.theta_rad + m0.yaw_rad, std::max(p_.range_sigma_m, 0.01), across));
}

bool HumanTracker::nearMap(double x, double y) const {
  for (const auto& s : map_)
    if (geometry::pointSegmentDistance({x, y}, s) < p_.map_margin_m) return true;
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
  person_echo_.fill(false);
  SonarEchoes echo{};
  for (std::size_t i = 0; i < 4; ++i)
    if (const auto e = echoOf(i, pose, ranges_m[i], t_s)) echo[i] = *e;
  placeLoneFrontEcho(pose, ranges_m, echo);
  triangulateFrontPair(pose, echo);
  for (std::size_t i = 0; i < 4; ++i)
    if (echo[i].use) associate(i, pose, ranges_m, echo, t_s);
  markContradicted(pose, ranges_m, t_s);
  classifyTracks(t_s);
  dropTracks(t_s);
}

std::optional<SonarEcho> HumanTracker::echoOf(std::size_t i, const control::Pose2& pose, double r, double t_s) {
  if (!(r > 0) || !std::isfinite(r) || r >= sonar_.max_range_m) return std::nullopt;
  ++counters_.echoes;
  const control::Pose2 sensor = config::mountPose(pose, sonar_.mounts[i]);
  const double bx = sensor.x_m, by = sensor.y_m, yaw = sensor.theta_rad;
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
    return std::nullopt;
  }
  // The same for the walls the side sensors traced (no map needed): a
  // corridor's walls reach the front cones' edges at a range that slides
  // along with the robot, as a leading person's would.
  const bool side_sensor = std::abs(std::remainder(sonar_.mounts[i].yaw_rad, M_PI)) > M_PI / 4;
  for (int k = -3; k <= 3 && !explained && p_.wall_trace && !side_sensor; k += 6) {
    const double a = yaw + k * sonar_.beam_width_rad / 6.0;
    explained = nearLearned(bx + r * std::cos(a), by + r * std::sin(a), t_s);
  }
  if (explained) {
    ++counters_.static_learned;
    // A track started on this echo before the wall was learned (the first
    // few tenths of a second of driving) goes: the echo that fed it is the wall's.
    std::erase_if(tracks_, [&](const HumanTrack& t) {
      const bool wall = std::hypot(t.x[0] - px, t.x[1] - py) < p_.gate_m;
      if (wall && !t.confirmed) ++counters_.tracks_unconfirmed_dropped;
      return wall;
    });
    return std::nullopt;
  }
  // Persistence: a person passes through a 0.2 m cell in well under a
  // second; structure keeps being hit in the same place for longer. Echoes
  // at a tracked person are exempt: a person who stops is still a person.
  bool at_person = false;
  for (const auto& t : tracks_)
    at_person = at_person || (t.isPerson() && std::hypot(t.x[0] - px, t.x[1] - py) < p_.gate_m);
  if (Cell* ce = cell(px, py); ce && !at_person) {
    const auto now = static_cast<float>(t_s);
    if (ce->last_s < 0 || now - ce->last_s > p_.grid_forget_s) ce->first_s = now;
    ce->last_s = now;
    if (now - ce->first_s > p_.grid_static_s) {
      ++counters_.static_grid;
      return std::nullopt;
    }
  }
  if (p_.wall_trace && side_sensor && tracesWall(i, Eigen::Vector2d(px, py), pose, t_s)) {
    ++counters_.static_wall_trace;
    // A track started on this wall before the trace was long enough goes too.
    std::erase_if(tracks_, [&](const HumanTrack& t) {
      const bool wall = !t.isPerson() && std::hypot(t.x[0] - px, t.x[1] - py) < p_.gate_m;
      if (wall && !t.confirmed) ++counters_.tracks_unconfirmed_dropped;
      return wall;
    });
    return std::nullopt;
  }
  // Measurement covariance: range noise along the beam, the cone's width across it.
  const double along = std::max(p_.range_sigma_m, 0.01);
  const double across = std::max(0.05, r * std::tan(sonar_.beam_width_rad / 2) / 2);
  return SonarEcho{true, Eigen::Vector2d(px, py), beamCovariance(yaw, along, across), r, yaw};
}

void HumanTracker::placeLoneFrontEcho(const control::Pose2& pose, const std::array<double, 4>& ranges_m,
                                      SonarEchoes& echo) const {
  if (!p_.triangulate_front || echo[0].use == echo[1].use || (ranges_m[0] > 0 && ranges_m[1] > 0)) return;
  const std::size_t i = echo[0].use ? 0 : 1, o = 1 - i;
  const auto& mi = sonar_.mounts[i];
  const auto& mo = sonar_.mounts[o];
  if (std::abs(mi.yaw_rad - mo.yaw_rad) >= 1e-6) return;
  const double side = (mi.y_m - mo.y_m) * std::cos(mi.yaw_rad) - (mi.x_m - mo.x_m) * std::sin(mi.yaw_rad);
  const double r = echo[i].range, half = sonar_.beam_width_rad / 2;
  const double shift = std::copysign(r * std::tan(half) / 2, side);  // centre of the outer half
  const double yaw = pose.theta_rad + mi.yaw_rad;
  echo[i].z += Eigen::Vector2d(-std::sin(yaw), std::cos(yaw)) * shift;
  echo[i].r = beamCovariance(yaw, std::max(p_.range_sigma_m, 0.01), std::max(0.05, r * std::tan(half) / 4));
}

void HumanTracker::triangulateFrontPair(const control::Pose2& pose, SonarEchoes& echo) {
  if (!p_.triangulate_front || !echo[0].use || !echo[1].use) return;
  if (const auto fused = triangulate(pose, echo[0].range, echo[1].range)) {
    echo[0].z = fused->first;
    echo[0].r = fused->second;
    echo[1].use = false;
    ++counters_.triangulated;
  }
}

Eigen::Matrix2d HumanTracker::rangeOnly(const SonarEcho& e) const {
  return beamCovariance(e.yaw, std::max(p_.range_sigma_m, 0.01),
                        std::max(0.1, e.range * std::tan(sonar_.beam_width_rad / 2)));
}

HumanTrack* HumanTracker::cameraTrackNear(const control::Pose2& pose, const SonarEcho& e, double t_s) {
  // A track the camera placed (its range from the foot row, +-25 %) may be
  // metres off along its bearing, and a front echo's lateral place (one
  // cone, or the two ranges' trilateration) a metre off across it: an echo
  // within a detection's error of a track the camera saw in the last
  // bearing_hold_s is that person, not a second one. The gate is one
  // detection's error, not the track's covariance: a person's foot-row error
  // is much the same picture after picture, so averaging does not shrink it.
  const Eigen::Matrix2d echo_r = rangeOnly(e);
  HumanTrack* best = nullptr;
  double best_d2 = p_.camera.gate_chi2;
  for (auto& t : tracks_) {
    if (!cameraSeenAt(t, t_s)) continue;
    const Eigen::Vector2d v = e.z - t.x.head<2>();
    const double r = std::hypot(t.x[0] - pose.x_m, t.x[1] - pose.y_m);
    const double yaw = std::atan2(t.x[1] - pose.y_m, t.x[0] - pose.x_m);
    const Eigen::Matrix2d s = beamCovariance(yaw, std::max(0.05, p_.camera.range_sigma_frac * r),
                                             std::max(0.05, r * p_.camera.bearing_sigma_deg * M_PI / 180.0)) +
                              echo_r;
    const double d2 = v.dot(s.ldlt().solve(v));
    if (d2 < best_d2) {
      best_d2 = d2;
      best = &t;
    }
  }
  return best;
}

void HumanTracker::associate(std::size_t i, const control::Pose2& pose, const std::array<double, 4>& ranges_m,
                             const SonarEchoes& echo, double t_s) {
  const SonarEcho& e = echo[i];
  HumanTrack* best = nullptr;
  double best_d = p_.gate_m;
  for (auto& t : tracks_) {
    const double d = std::hypot(t.x[0] - e.z.x(), t.x[1] - e.z.y());
    if (d < best_d) {
      best_d = d;
      best = &t;
    }
  }
  if (!best) {
    best = cameraTrackNear(pose, e, t_s);
    if (best) ++counters_.camera_echo_joins;
  }
  if (best) {
    // A track the camera saw lately has its bearing from the camera: the
    // echo gives it range only, or its 100 echoes a second, each placed on
    // the beam's centre line, would outweigh the bearings and pull a
    // crossing person back to the centre.
    update(*best, e.z, cameraSeenAt(*best, t_s) ? rangeOnly(e) : e.r, t_s);
    ++counters_.associated;
    const bool person = best->isPerson();
    person_echo_[i] = person;
    if (i == 0 && p_.triangulate_front && !echo[1].use && ranges_m[1] > 0) person_echo_[1] = person;
  } else if (static_cast<int>(tracks_.size()) < p_.max_tracks && e.range < sonar_.max_range_m - p_.new_track_margin_m) {
    tracks_.push_back(newTrack(e.z, e.r, t_s));
    ++counters_.tracks_created;
  }
}

HumanTrack HumanTracker::newTrack(const Eigen::Vector2d& z, const Eigen::Matrix2d& r, double t_s) {
  HumanTrack t;
  t.id = next_id_++;
  t.x << z.x(), z.y(), 0, 0;
  t.p = Eigen::Matrix4d::Zero();
  t.p.block<2, 2>(0, 0) = r;
  t.p(2, 2) = t.p(3, 3) = 1.0;  // unknown velocity: up to ~1-2 m/s
  t.first_seen_s = t.last_seen_s = t_s;
  t.hits = 1;
  return t;
}

void HumanTracker::markContradicted(const control::Pose2& pose, const std::array<double, 4>& ranges_m, double t_s) {
  for (auto& t : tracks_) {
    if (t.last_seen_s >= t_s) {
      t.contradicted = 0;
      continue;
    }
    bool contradicted = false;
    for (std::size_t i = 0; i < 4 && !contradicted; ++i) {
      const control::Pose2 sensor = config::mountPose(pose, sonar_.mounts[i]);
      const double dx = t.x[0] - sensor.x_m, dy = t.x[1] - sensor.y_m, d = std::hypot(dx, dy);
      if (d < 0.1 || d > sonar_.max_range_m - 0.3) continue;
      const double bearing = std::remainder(std::atan2(dy, dx) - sensor.theta_rad, 2 * M_PI);
      if (std::abs(bearing) > 0.6 * sonar_.beam_width_rad / 2) continue;
      const double r = ranges_m[i];
      contradicted = !(r > 0) || !std::isfinite(r) || r > d + p_.contradiction_margin_m;
    }
    t.contradicted = contradicted ? t.contradicted + 1 : 0;
  }
}

void HumanTracker::classifyTracks(double t_s) {
  for (auto& t : tracks_) {
    const bool enough = t.hits >= p_.confirm_hits || t.camera_hits >= p_.camera.confirm_hits;
    if (!t.confirmed && enough && t.last_seen_s - t.first_seen_s <= p_.confirm_window_s + 1e-9) {
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
    // Once a person, standing still keeps it one for person_hold_s.
    if (t.confirmed && t.moving_since_s >= 0 && t_s - t.moving_since_s >= p_.moving_for_s) t.person = true;
    // What the camera confirms is a person, moving or not.
    if (t.confirmed && t.camera_hits >= p_.camera.confirm_hits && t.person_logodds >= p_.camera.person_logodds)
      t.person = true;
  }
}

void HumanTracker::dropTracks(double t_s) {
  std::erase_if(tracks_, [&](const HumanTrack& t) {
    if (t.contradicted >= p_.contradiction_ticks) {
      ++counters_.tracks_contradicted;
      if (!t.confirmed) ++counters_.tracks_unconfirmed_dropped;
      return true;
    }
    if (t_s - t.last_seen_s > p_.coast_s) {
      if (!t.confirmed) ++counters_.tracks_unconfirmed_dropped;
      return true;
    }
    if (!t.confirmed && t_s - t.first_seen_s > p_.confirm_window_s && t.hits < p_.confirm_hits &&
        t.camera_hits < p_.camera.confirm_hits) {
      ++counters_.tracks_unconfirmed_dropped;
      return true;
    }
    if (t.slow_since_s >= 0 && t_s - t.slow_since_s > (t.person ? p_.person_hold_s : p_.static_after_s)) {
      ++counters_.tracks_static_dropped;
      return true;
    }
    return false;
  });
}

bool HumanTracker::tracesWall(std::size_t i, const Eigen::Vector2d& z, const control::Pose2& pose, double t_s) {
  Trace& tr = traces_[i];
  tr.point[tr.head] = z;
  tr.robot[tr.head] = {pose.x_m, pose.y_m};
  tr.t[tr.head] = t_s;
  tr.head = (tr.head + 1) % Trace::kSize;
  tr.count = std::min(tr.count + 1, Trace::kSize);
  // The points of the window, oldest first.
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  std::size_t n = 0;
  std::size_t oldest = tr.head;  // index of the oldest point within the window
  for (std::size_t k = 0; k < tr.count; ++k) {
    const std::size_t j = (tr.head + Trace::kSize - 1 - k) % Trace::kSize;
    if (t_s - tr.t[j] > p_.wall_trace_s) break;
    mean += tr.point[j];
    ++n;
    oldest = j;
  }
  if (n < 10 || t_s - tr.t[oldest] < 0.6 * p_.wall_trace_s) return false;
  mean /= static_cast<double>(n);
  Eigen::Matrix2d c = Eigen::Matrix2d::Zero();
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t j = (tr.head + Trace::kSize - 1 - k) % Trace::kSize;
    const Eigen::Vector2d d = tr.point[j] - mean;
    c += d * d.transpose();
  }
  c /= static_cast<double>(n);
  // Principal axis of the points (2x2 symmetric eigenproblem in closed form).
  const double tr_c = c(0, 0) + c(1, 1), det = c(0, 0) * c(1, 1) - c(0, 1) * c(0, 1);
  const double disc = std::sqrt(std::max(0.0, tr_c * tr_c / 4 - det));
  const double major = tr_c / 2 + disc, minor = std::max(0.0, tr_c / 2 - disc);
  if (std::sqrt(minor) > p_.wall_trace_width_m) return false;
  const double axis = 0.5 * std::atan2(2 * c(0, 1), c(0, 0) - c(1, 1));
  const double off = std::abs(std::remainder(axis - pose.theta_rad, M_PI));
  if (off > p_.wall_trace_angle_deg * M_PI / 180.0) return false;
  // Spread as far as the robot moved (the echo slid with it; a standing
  // object's echo points would stay put and go to the persistence grid).
  const double moved = (tr.robot[(tr.head + Trace::kSize - 1) % Trace::kSize] - tr.robot[oldest]).norm();
  const double spread = (tr.point[(tr.head + Trace::kSize - 1) % Trace::kSize] - tr.point[oldest]).norm();
  if (!(moved > 0.03 && std::sqrt(major) > 0.01 && spread > 0.6 * moved && spread < 1.5 * moved)) return false;
  // Remember the wall: the line through the points' mean along the robot's
  // heading, from a metre behind to 5 m ahead (the front cones' reach). Not
  // the points' own principal axis: over half a second of driving (0.25 m
  // at 0.5 m/s) with 2 cm of range noise it is known to only ~5 deg, 0.4 m
  // at the front cones' 4 m; the heading is what the trace was checked against.
  const Eigen::Vector2d dir(std::cos(pose.theta_rad), std::sin(pose.theta_rad));
  const Eigen::Vector2d from = mean - (0.5 * spread + 1.0) * dir, to = mean + (0.5 * spread + 5.0) * dir;
  learned_[i] = {{{from.x(), from.y()}, {to.x(), to.y()}}, t_s};
  return true;
}

bool HumanTracker::nearLearned(double x, double y, double t_s) const {
  constexpr double kLearnedFor_s = 2.0;  // a traced wall holds this long after its last confirmation
  // The fitted line's direction is known to ~2 deg: ~0.15 m at the front cones' 4 m.
  const double margin = std::max(p_.map_margin_m, 0.3);
  for (const auto& l : learned_)
    if (l.t_s >= 0 && t_s - l.t_s < kLearnedFor_s && geometry::pointSegmentDistance({x, y}, l.wall) < margin)
      return true;
  return false;
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
