#pragma once
// What a tuning session leaves behind (docs/tuning.md): controllers compared
// on the tuner's reference and plant (robust figures over the scenarios and a
// nominal trace for plots), a console table, and the session directory with
// summary.md, results.json, the tuned gains (YAML + .fis) and the paper's
// Fig 20-style plots.
#include <string>
#include <vector>

#include "pc_server/tuning/tuner.hpp"
#include "shared/control/gain_set.hpp"
#include "shared/control/trajectory_tracker.hpp"
#include "shared/fuzzy/fis.hpp"
#include "sim/closed_loop.hpp"

namespace inspect::tuning {

/// One controller to compare: a wheel loop and the gains it runs with.
struct ControllerCase {
  std::string label;  // e.g. "PID", "fuzzy-PID (paper)", "fuzzy-PID (tuned)"
  control::WheelControl wheel_control = control::WheelControl::kFuzzyPid;
  control::GainSet gains;
};

/// A case's figures.
struct ComparisonRow {
  std::string label;
  control::WheelControl wheel_control = control::WheelControl::kFuzzyPid;
  control::GainSet gains;
  Evaluation eval;            // robust, over the tuner's scenarios (Tuner::evaluate)
  sim::ClosedLoopResult trace;  // the setup's plant, noise seed 1, with samples (Tuner::trace)
};

struct Comparison {
  std::string reference;          // TuneReference::describe()
  std::string plant_description;  // per wheel: gain, time constant, dead time, saturation
  std::vector<ComparisonRow> rows;
};

/// Evaluates and traces every case with the tuner (its reference, plant and scenarios).
/// The plant as compact JSON ({"left": {gain, time_constant_s, dead_time_s,
/// saturation_rad_s}, "right": {...}}), as results.json and the catalog keep it.
std::string plantJson(const control::PlantModel& p);

Comparison compareControllers(const Tuner& tuner, const std::vector<ControllerCase>& cases);

/// Fixed-width text table for the console, one column per case: max / RMS
/// position and angle error, position / angle convergence time, effort and
/// saturation time on the nominal trace, then the worst max errors over the
/// scenarios and the robust cost. Ends with a newline.
std::string comparisonTable(const Comparison& c);

/// The files of a session directory.
struct SessionFiles {
  std::string dir;
  std::vector<std::string> files;  // paths of the files written, in the order written
  std::vector<std::string> notes;  // what could not be drawn and why (e.g. gnuplot missing)
};

/// Creates `dir` and writes summary.md, results.json, traces.csv,
/// gains_tuned.yaml + gains_tuned.fis (config::exportGains, result.best with
/// `fis`), fig20_position_error.png, fig20_angle_error.png, trajectory.png and
/// cost_history.png. When a plot cannot be drawn (gnuplot missing or failing)
/// its gnuplot script with the data inline (<name>.png.gp) is kept instead and
/// the reason is in notes and summary.md. Throws std::runtime_error (or
/// config::ConfigError for the gains files) when a file cannot be written.
SessionFiles writeTuningSession(const std::string& dir, const TuneSetup& setup, const TuneResult& result,
                                const Comparison& c, const fuzzy::Fis& fis);

}  // namespace inspect::tuning
