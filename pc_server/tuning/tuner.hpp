#pragma once
// The fuzzy-PID tuner (docs/tuning.md): closed-loop simulations of a
// reference path with the tracker the robot runs (sim/closed_loop.hpp) on a
// plant model (nominal or identified), a documented cost, and NLopt's
// derivative-free global search followed by a local polish. Each candidate is
// evaluated over plant variations x noise seeds (robustness); the runs of one
// evaluation are spread over worker threads.
#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "shared/config/control_config.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/control/gain_set.hpp"
#include "shared/control/plant_model.hpp"
#include "shared/control/reference_path.hpp"
#include "shared/fuzzy/fis.hpp"
#include "sim/closed_loop.hpp"

namespace inspect::tuning {

/// The reference the tuner tracks; the path starts at the origin facing +x.
struct TuneReference {
  enum class Kind { kCircle, kLine, kWaypoints };
  Kind kind = Kind::kCircle;
  double radius_m = 3.5;   // circle (the paper's)
  double speed_m_s = 0.5;
  double laps = 1.0;
  double length_m = 10.0;  // line; waypoints: a length x length/2 rectangle
  std::string describe() const;
  std::unique_ptr<control::ReferencePath> makePath() const;
};

/// Weights of the cost terms; every term is normalised by its scale (see
/// costOf()), so a weight of 1 means "one scale unit is worth 1".
///
/// Cost of one run (costOf), with E_ref the reference's own effort:
///   c = max_pos  * max_pos_err_m / 0.05      + rms_pos * rms_pos_err_m / 0.01
///     + max_ang  * max_ang_err_rad / 0.05    + rms_ang * rms_ang_err_rad / 0.01
///     + convergence * (converge_pos_s + converge_ang_s) / 2 / 10
///     + effort * max(0, effort / E_ref - 1)             (0 when E_ref <= 0)
///     + saturation * 10 * saturated_s / duration_s
///     + 50 for each of position and angle not converged (still outside its band
///       at the end of the run: converge_*_s >= duration_s - 0.005 s)
/// A diverged run (a non-finite metric, or max position error > 1 m) costs
/// 1e4 + min(max_pos_err_m, 1000) (or 2e4 when not finite): large, finite, and
/// still larger the further it went. The cost never decreases when a metric grows.
/// Evaluation cost over the S scenarios: mean(c_i) + max(c_i).
struct CostWeights {
  double max_pos = 1.0;      // max position error / 0.05 m
  double rms_pos = 1.0;      // RMS position error / 0.01 m
  double max_ang = 1.0;      // max angle error / 0.05 rad
  double rms_ang = 1.0;      // RMS angle error / 0.01 rad
  double convergence = 0.5;  // (position + angle convergence time) / 2 / 10 s
  double effort = 0.2;       // effort relative to the reference's own (feed-forward) effort, minus 1
  double saturation = 1.0;   // fraction of the run with a wheel at its limit x 10
};

struct TuneSetup {
  config::RobotConfig robot;
  config::ControlConfig control;      // the paper defaults (config/control.yaml): start point and the rest of the tracker
  fuzzy::Fis fis;                     // the fuzzy-PID system (config/fuzzy/fuzzy_pid.fis)
  control::PlantModel plant;          // the plant to tune for (nominal or identified)
  TuneReference reference;
  std::vector<std::string> params{"kp", "ki", "kd", "ke", "kec", "k1", "k2", "k3"};  // names of control::kGainNames
  std::map<std::string, std::pair<double, double>> bounds;  // per-name overrides of defaultTuneBounds()
  CostWeights weights;
  // Variation 0 is the plant; the others put each wheel's gain (x 1 +- gain_spread), time constant
  // (x 1 +- tau_spread) and dead time (+ 0 .. dead_spread_s) on a Latin hypercube that includes the
  // extremes, permuted by `seed`.
  int plant_variations = 4;   // 1 = the plant only
  double gain_spread = 0.10;  // +- fraction, [0, 1)
  double tau_spread = 0.30;   // +- fraction, [0, 1)
  double dead_spread_s = 0.02;  // added dead time, [0, 1] s
  int seeds = 2;              // noise seeds per plant variation: seed, seed + 1, ...
  int max_evals = 1000;
  int threads = 0;            // 0 = std::thread::hardware_concurrency()
  double global_fraction = 0.7;  // share of max_evals for the global phase; the rest polishes locally
  std::string global_algorithm = "GN_CRS2_LM";  // or GN_ISRES, GN_DIRECT_L, GN_ESCH (NLopt names)
  std::string local_algorithm = "LN_SBPLX";     // or LN_BOBYQA, LN_NELDERMEAD, LN_COBYLA
  uint32_t seed = 1;          // plant variations (Latin hypercube), noise seeds (seed + j), NLopt's random numbers
};

/// Search range the tuner uses for a gain unless TuneSetup::bounds overrides it.
std::pair<double, double> defaultTuneBounds(const std::string& name);

/// One candidate over all scenarios (variations x seeds).
struct Evaluation {
  double cost = 0.0;               // mean of the per-scenario costs + max of them (robust)
  sim::ClosedLoopMetrics mean;     // per-metric mean over the scenarios
  sim::ClosedLoopMetrics worst;    // per-metric worst over the scenarios
  sim::ClosedLoopMetrics nominal;  // the plant itself, first seed
  int scenarios = 0;
};

/// The cost of one run (the documented formula).
double costOf(const sim::ClosedLoopMetrics& m, const CostWeights& w, double reference_effort);

struct TuneProgress {
  int evals = 0;
  int max_evals = 0;
  double best_cost = 0.0;
  double initial_cost = 0.0;
  control::GainSet best;
  double elapsed_s = 0.0;
  std::string phase;  // "global" or "local"
};

struct TuneResult {
  control::GainSet initial, best;
  Evaluation initial_eval, best_eval;
  int evals = 0;
  bool cancelled = false;
  double wall_s = 0.0;
  std::string algorithm;  // e.g. "GN_CRS2_LM + LN_SBPLX"
  std::vector<double> best_cost_history;  // best cost after each evaluation
};

class Tuner {
 public:
  /// Throws std::invalid_argument naming the problem: unknown parameter name,
  /// empty parameter list, bounds not lo < hi or outside control::gainBounds,
  /// invalid plant (control::validatePlant), bad counts.
  explicit Tuner(TuneSetup setup);
  ~Tuner();

  const TuneSetup& setup() const;
  /// Evaluates a gain set (robust over the scenarios) with the given wheel controller.
  Evaluation evaluate(const control::GainSet& g,
                      control::WheelControl wc = control::WheelControl::kFuzzyPid) const;
  /// One closed-loop run on the setup's plant, with samples (for plots).
  sim::ClosedLoopResult trace(const control::GainSet& g, control::WheelControl wc, uint32_t seed = 1) const;
  /// Optimises setup().params from `start`. `progress` is called after each
  /// evaluation (from the calling thread); a set `cancel` stops at the next
  /// evaluation, keeping the best so far (result.cancelled = true).
  TuneResult run(const control::GainSet& start, const std::function<void(const TuneProgress&)>& progress,
                 const std::atomic<bool>* cancel);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace inspect::tuning
