#pragma once
// Closed-loop trajectory tracking in-process, far faster than real time: the
// tracker the robot runs (shared/control/trajectory_tracker.hpp) against the
// simulator's plant (first-order hub motors with saturation, the paper's
// geometry) and the MCU's measurement model (wheel speed +-0.002 m/s,
// heading +-0.002 rad, exact wheel travel). Used by the circle experiment and
// the tuner.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "shared/config/robot_config.hpp"
#include "shared/control/plant_model.hpp"
#include "shared/control/trajectory_tracker.hpp"

namespace inspect::sim {

struct ClosedLoopConfig {
  config::RobotConfig robot;
  control::TrackerParams tracker;
  double control_dt_s = 0.01;     // the paper's sampling time
  double physics_dt_s = 0.001;    // plant integration step
  double extra_time_s = 0.0;      // keep simulating (reference parked) after the path ends
  std::optional<control::PlantModel> plant;  // the true motors; nominalPlant(robot) when empty
  bool noise = true;
  uint32_t seed = 1;
  double settle_position_m = 0.01;  // convergence bands (see docs/controllers.md)
  double settle_angle_rad = 0.01;
};

/// One control tick.
struct ClosedLoopSample {
  double t_s;
  control::Pose2 pose;   // true pose
  control::Pose2 ref;    // reference pose
  double pos_err_m;      // |(x_e, y_e)| of the true pose
  double ang_err_rad;    // |theta_e|
  control::WheelSpeeds wheel;    // true wheel speeds
  control::WheelSpeeds command;  // sent to the motors
  control::PidGains gains_left;
};

/// Figures of one run (definitions in docs/controllers.md).
struct ClosedLoopMetrics {
  double max_pos_err_m = 0;
  double max_ang_err_rad = 0;
  double rms_pos_err_m = 0;
  double rms_ang_err_rad = 0;
  double converge_pos_s = 0;   // last time the error was outside the band (0: never left it)
  double converge_ang_s = 0;
  double effort = 0;           // integral of (u_l^2 + u_r^2) dt, rad^2/s
  double command_variation = 0;  // sum |delta u| over both wheels, rad/s
  double saturated_s = 0;      // time with a wheel command at the limit
  double duration_s = 0;
  double final_pos_err_m = 0;
};

struct ClosedLoopResult {
  ClosedLoopMetrics metrics;
  std::vector<ClosedLoopSample> samples;  // filled when asked
};

/// Runs the path from its start pose (the robot starts on it, at rest).
ClosedLoopResult runClosedLoop(const ClosedLoopConfig& cfg, std::unique_ptr<control::ReferencePath> path,
                               std::shared_ptr<control::FuzzyGainScheduler> scheduler, bool keep_samples);

/// Distance of each sample's true position from the reference polyline
/// (px, py): the shape error of Fig 18, without the along-track lag. Progress
/// along the path is monotone, so the search runs in a window around the last
/// match. NaN for every sample when the polyline has fewer than 2 points.
std::vector<double> distanceFromPath(const std::vector<double>& px, const std::vector<double>& py,
                                     const std::vector<ClosedLoopSample>& samples);

/// A run as the trajectory plots draw it (Fig 18 and the tuning report): its
/// path (x, y), and its distance from the reference polyline over time.
struct TrackTrace {
  std::vector<double> x_m, y_m;    // the robot's path
  std::vector<double> t_s, distance_m;  // distanceFromPath over time
};
TrackTrace trackTrace(const std::vector<double>& px, const std::vector<double>& py,
                      const std::vector<ClosedLoopSample>& samples);

/// Convergence time of a series: the time after which |value| stays <= band.
double convergenceTime(const std::vector<double>& t, const std::vector<double>& value, double band);

}  // namespace inspect::sim
