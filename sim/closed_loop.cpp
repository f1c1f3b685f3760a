#include "sim/closed_loop.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "sim/robot_plant.hpp"
#include "sim/world_names.hpp"

namespace inspect::sim {

TrackTrace trackTrace(const std::vector<double>& px, const std::vector<double>& py,
                      const std::vector<ClosedLoopSample>& samples) {
  TrackTrace t;
  t.distance_m = distanceFromPath(px, py, samples);
  for (const auto& s : samples) {
    t.x_m.push_back(s.pose.x_m);
    t.y_m.push_back(s.pose.y_m);
    t.t_s.push_back(s.t_s);
  }
  return t;
}

std::vector<double> distanceFromPath(const std::vector<double>& px, const std::vector<double>& py,
                                     const std::vector<ClosedLoopSample>& samples) {
  std::vector<double> out;
  out.reserve(samples.size());
  const std::size_t n = px.size();
  if (n < 2) return std::vector<double>(samples.size(), std::numeric_limits<double>::quiet_NaN());
  std::size_t j = 0;
  for (const auto& s : samples) {
    double best = std::numeric_limits<double>::infinity();
    std::size_t best_j = j;
    const std::size_t lo = j > 200 ? j - 200 : 0, hi = std::min(n - 1, j + 400);
    for (std::size_t k = lo; k < hi; ++k) {
      const double ax = px[k], ay = py[k], bx = px[k + 1] - ax, by = py[k + 1] - ay;
      const double len2 = bx * bx + by * by;
      const double u = len2 > 0 ? std::clamp(((s.pose.x_m - ax) * bx + (s.pose.y_m - ay) * by) / len2, 0.0, 1.0) : 0.0;
      const double d = std::hypot(s.pose.x_m - ax - u * bx, s.pose.y_m - ay - u * by);
      if (d < best) {
        best = d;
        best_j = k;
      }
    }
    j = best_j;
    out.push_back(best);
  }
  return out;
}

double convergenceTime(const std::vector<double>& t, const std::vector<double>& value, double band) {
  for (std::size_t i = std::min(t.size(), value.size()); i-- > 0;)
    if (std::abs(value[i]) > band) return i + 1 < t.size() ? t[i + 1] : t[i];
  return 0.0;
}

ClosedLoopResult runClosedLoop(const ClosedLoopConfig& cfg, std::unique_ptr<control::ReferencePath> path,
                               std::shared_ptr<control::FuzzyGainScheduler> scheduler, bool keep_samples) {
  const World empty{};
  const RobotPlant plant(cfg.robot, empty, cfg.plant ? *cfg.plant : nominalPlant(cfg.robot));
  control::SetpointDelay delay(plant.motors().left.dead_time_s, plant.motors().right.dead_time_s);
  const double path_time = [&] {
    // Nominal duration: integrate ds / v over the path.
    double t = 0, s = 0;
    const double len = path->length_m();
    while (s < len) {
      const double v = std::max(1e-3, path->at(s).speed_m_s);
      const double ds = std::min(0.01, len - s);
      t += ds / v;
      s += ds;
    }
    return t;
  }();
  const control::Pose2 start = path->at(0.0).pose;
  control::TrajectoryTracker tracker(std::move(path), cfg.tracker, std::move(scheduler));

  std::mt19937 rng(cfg.seed);
  const double r = cfg.robot.geometry.wheel_radius_m;
  std::uniform_real_distribution<double> speed_noise(-cfg.robot.motor.speed_noise_m_s / r,
                                                     cfg.robot.motor.speed_noise_m_s / r);
  std::uniform_real_distribution<double> heading_noise(-cfg.robot.motor.heading_noise_rad,
                                                       cfg.robot.motor.heading_noise_rad);

  PlantState st;
  st.pose = start;
  control::Pose2 est = start;  // the robot's own estimate, as robot_client computes it
  double travel_l = 0, travel_r = 0;
  control::WheelSpeeds cmd{};
  const int substeps = std::max(1, static_cast<int>(std::lround(cfg.control_dt_s / cfg.physics_dt_s)));
  const double phys_dt = cfg.control_dt_s / substeps;
  const int ticks = static_cast<int>(std::ceil((path_time + cfg.extra_time_s) / cfg.control_dt_s));

  ClosedLoopResult res;
  std::vector<double> ts, pe, ae;
  ts.reserve(static_cast<std::size_t>(ticks));
  pe.reserve(static_cast<std::size_t>(ticks));
  ae.reserve(static_cast<std::size_t>(ticks));
  if (keep_samples) res.samples.reserve(static_cast<std::size_t>(ticks));
  auto& m = res.metrics;
  double sum_pe2 = 0, sum_ae2 = 0;
  control::WheelSpeeds prev_cmd{};
  for (int k = 0; k < ticks; ++k) {
    const double t = (k + 1) * cfg.control_dt_s;
    for (int i = 0; i < substeps; ++i)
      st = plant.step(st, delay.apply((k * substeps + i) * phys_dt, cmd), phys_dt).state;
    // What the MCU reports: noisy wheel speeds and heading, exact travel.
    const double dl = st.wheel_travel_left_m - travel_l, dr = st.wheel_travel_right_m - travel_r;
    travel_l = st.wheel_travel_left_m;
    travel_r = st.wheel_travel_right_m;
    control::WheelSpeeds meas = st.wheel;
    double heading = st.pose.theta_rad;
    if (cfg.noise) {
      meas.left_rad_s += speed_noise(rng);
      meas.right_rad_s += speed_noise(rng);
      heading += heading_noise(rng);
    }
    est = control::odometryWithHeading(est, dl, dr, heading);
    const auto out = tracker.step(est, meas, 1.0, cfg.control_dt_s);
    cmd = plant.clampSetpoint(out.command);
    // Errors of the TRUE pose against the reference (what a ruler would measure).
    const auto e = control::trackingError(st.pose, out.ref.pose);
    const double pos = e.position_m(), ang = std::abs(e.theta_rad);
    ts.push_back(t);
    pe.push_back(pos);
    ae.push_back(ang);
    m.max_pos_err_m = std::max(m.max_pos_err_m, pos);
    m.max_ang_err_rad = std::max(m.max_ang_err_rad, ang);
    sum_pe2 += pos * pos;
    sum_ae2 += ang * ang;
    m.effort += (cmd.left_rad_s * cmd.left_rad_s + cmd.right_rad_s * cmd.right_rad_s) * cfg.control_dt_s;
    m.command_variation += std::abs(cmd.left_rad_s - prev_cmd.left_rad_s) + std::abs(cmd.right_rad_s - prev_cmd.right_rad_s);
    prev_cmd = cmd;
    const double lim = cfg.robot.limits.max_wheel_speed_rad_s - 1e-9;
    if (std::abs(cmd.left_rad_s) >= lim || std::abs(cmd.right_rad_s) >= lim) m.saturated_s += cfg.control_dt_s;
    if (keep_samples)
      res.samples.push_back({t, st.pose, out.ref.pose, pos, ang, st.wheel, cmd, tracker.lastGains(0)});
  }
  const double n = std::max<std::size_t>(1, ts.size());
  m.rms_pos_err_m = std::sqrt(sum_pe2 / n);
  m.rms_ang_err_rad = std::sqrt(sum_ae2 / n);
  m.converge_pos_s = convergenceTime(ts, pe, cfg.settle_position_m);
  m.converge_ang_s = convergenceTime(ts, ae, cfg.settle_angle_rad);
  m.duration_s = ts.empty() ? 0 : ts.back();
  m.final_pos_err_m = pe.empty() ? 0 : pe.back();
  return res;
}

}  // namespace inspect::sim
