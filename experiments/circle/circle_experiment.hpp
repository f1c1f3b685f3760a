#pragma once
// The circle experiment's parts (experiments/circle): its options, the
// metrics of a run next to the paper's figures (section 5.2, Table 3), the
// plots (Figs 18, 20). track_experiment.cpp runs it.
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "shared/control/pid_controller.hpp"
#include "shared/control/reference_path.hpp"
#include "shared/control/trajectory_tracker.hpp"
#include "shared/util/cli_args.hpp"
#include "sim/closed_loop.hpp"

namespace inspect::circle {

using control::WheelControl;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

using cli::UsageError;

enum class Trajectory { kCircle, kLine, kWaypoints };

const char* toString(Trajectory t);

struct Options {
  Trajectory trajectory = Trajectory::kCircle;
  double radius_m = 3.5;
  double speed_m_s = 0.5;
  double laps = 1.0;
  double length_m = 10.0;
  std::vector<WheelControl> controllers{WheelControl::kPid, WheelControl::kFuzzyPid};
  std::string robot_path = "config/robot.yaml";
  std::string control_path = "config/control.yaml";
  uint32_t seed = 1;
  int seeds = 1;
  bool noise = true;
  double dead_time_s = 0.0;  // the motors' dead time: a command reaches them this late
  double band_m = 0.01;
  double band_rad = 0.01;
  std::string plots_dir;
  std::string json_path;
  bool help = false;
};

/// The command line; throws UsageError naming the flag.
Options parseArgs(int argc, char** argv);
/// The --help text.
extern const char* const kUsage;

/// The reference path of the options.
std::unique_ptr<control::ReferencePath> makePath(const Options& o);


/// One row of the table: how to read it from a run, and the paper's figures.
struct MetricDef {
  const char* key;    // JSON key
  const char* label;  // table label
  int decimals;
  std::optional<double> paper_pid;
  std::optional<double> paper_fuzzy;
};

enum Metric : std::size_t {
  kMaxPos,
  kMaxAng,
  kConvPos,
  kConvAng,
  kRmsPos,
  kRmsAng,
  kEffort,
  kVariation,
  kSaturation,
  kNumMetrics
};

// Paper section 5.2 (PAPER_DIGEST.md): fuzzy-PID max position error "less
// than 0.098 m" converged 18.25 s, max angle error "less than 0.088 rad"
// converged 20.05 s; PID 0.1 m / 25.76 s and 0.175 rad / 20.52 s.
inline const std::array<MetricDef, kNumMetrics> kMetrics{{
    {"max_position_error_m", "max position error (m)", 4, 0.1, 0.098},
    {"max_angle_error_rad", "max angle error (rad)", 4, 0.175, 0.088},
    {"position_convergence_s", "position convergence (s)", 2, 25.76, 18.25},
    {"angle_convergence_s", "angle convergence (s)", 2, 20.52, 20.05},
    {"rms_position_error_m", "RMS position error (m)", 4, std::nullopt, std::nullopt},
    {"rms_angle_error_rad", "RMS angle error (rad)", 4, std::nullopt, std::nullopt},
    {"control_effort_rad2_s", "control effort (rad^2/s)", 1, std::nullopt, std::nullopt},
    {"command_variation_rad_s", "command variation (rad/s)", 1, std::nullopt, std::nullopt},
    {"saturation_time_s", "saturation time (s)", 2, std::nullopt, std::nullopt},
}};

/// One closed-loop run and what is derived from it.
struct Run {
  WheelControl controller;
  uint32_t seed;
  sim::ClosedLoopResult result;
  double final_ang_err_rad = 0;
  bool pos_converged = true;
  bool ang_converged = true;
  double wall_s = 0;
  std::array<double, kNumMetrics> values{};  // NaN: not converged
};

/// "PID", "fuzzy-PID", "direct".
std::string label(WheelControl c);
/// A metric with `decimals`; "not conv." for NaN.
std::string fmt(double v, int decimals);


/// The paper's Table 3 "critical points": the start and each quarter lap.
struct CriticalPoint {
  double fraction;  // of one lap
  double paper_pos_m;
  double paper_ang_rad;
};
inline constexpr std::array<CriticalPoint, 5> kCritical{{{0.0, 0.0, 0.0},
                                                  {0.25, 0.014, 0.007},
                                                  {0.5, 0.001, 0.0},
                                                  {0.75, 0.0, 0.0},
                                                  {1.0, 0.0, 0.0}}};

/// Errors when the reference passes `fraction` of the first lap.
struct PointErrors {
  double t_s;
  double pos_m;
  double ang_rad;
};

/// The errors at a critical point; nothing if the run does not reach it.
/// Point 1 is the start, where the robot is placed: both errors are 0.
std::optional<PointErrors> errorsAtLapFraction(const Run& r, const Options& o, double fraction);

/// Fig 18, Fig 20 and the wheel-and-gain PNGs into o.plots_dir; "" or what went wrong.
std::string writePlots(const Options& o, const std::vector<const Run*>& runs, const control::PidGains& base,
                       std::vector<std::string>& written);

}  // namespace inspect::circle
