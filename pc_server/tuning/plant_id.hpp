#pragma once
// Hub-motor plant identification from recorded runs (docs/tuning.md): fits
// the per-wheel model of shared/control/plant_model.hpp,
//   w = gain e^(-dead_time s) / (time_constant s + 1) clamp(u, +-saturation),
// to the wheel set-points robot_client sent (u) and the wheel speeds the MCU
// reported (w), as recorded in a run's /telemetry.
//
// Method, per wheel:
//  1. Checks: equal lengths, finite values, strictly increasing time, enough
//     samples, a command that leaves +-min_excitation_rad_s at least once.
//  2. Resampling: the sample period is the median interval (50 Hz telemetry
//     with jitter -> 20 ms); the series is split wherever an interval exceeds
//     max_gap_s (link loss) and each stretch is linearly interpolated onto a
//     uniform grid of that period starting at its first sample.
//  3. Start point: for each dead time on a 5 ms grid in [0, max_dead_time_s],
//     a first-order ARX y[k+1] = a y[k] + b (u[k-d] + u[k+1-d]) / 2 by least squares
//     gives gain b / (1 - a) and time constant -T / ln a; each candidate is
//     simulated and the one with the smallest output error starts step 4.
//  4. Output-error refinement: (gain, time constant, dead time) minimise the
//     squared error of the SIMULATED speed against the measured one (exact
//     discretisation with the input linear between grid points, the delayed
//     input interpolated between samples so the dead time is continuous; each
//     stretch starts from its first measured value), with NLopt's LN_BOBYQA.
//     Unlike ARX, the output error is not biased by measurement noise.
//  5. Saturation: step 4 is repeated with the saturation as a fourth
//     parameter, started from the plateau (largest measured |speed| held over
//     0.1 s, / gain) and from 85, 70 and 50 % of the largest |command| (a
//     saturated run biases the 3-parameter gain low, so the plateau alone
//     misleads). It is kept, with saturation_observed, when it lowers the
//     squared error by at least 10 % and lies below 95 % of the largest
//     |command|; otherwise the saturation is nominal_saturation_rad_s.
// The dead time found includes robot_client's own loop latency (the command
// recorded with telemetry sample k was computed from an earlier frame): it
// is the plant as the controller sees it, which is what the tuner needs.
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "shared/control/plant_model.hpp"

namespace inspect::tuning {

/// One wheel's recorded signals, sample by sample.
struct WheelSeries {
  std::vector<double> t_s;             // sample times, strictly increasing (any origin)
  std::vector<double> command_rad_s;   // wheel set-point sent to the MCU
  std::vector<double> measured_rad_s;  // wheel speed the MCU reported
};

/// The model fitted to one wheel and how well it reproduces the run.
struct WheelFit {
  control::WheelMotorModel model;
  double rms_error_rad_s = 0.0;  // RMS of measured - simulated, over the resampled grid
  double fit_percent = 0.0;      // 100 (1 - |y - yhat| / |y - mean(y)|), MATLAB's NRMSE fit (100 = perfect)
  std::size_t samples = 0;       // resampled grid points the fit used
  bool saturation_observed = false;  // the run drove the wheel into its limit; else model.saturation_rad_s is nominal
};

/// Both wheels' fits, with the run's figures and what to be wary of.
struct PlantFit {
  control::PlantModel model;
  WheelFit left, right;
  double duration_s = 0.0;       // time spanned by the longer of the two series
  double sample_period_s = 0.0;  // resampling grid period (the median sample interval; the larger of the wheels')
  // Fit below 80 %, a wheel barely excited (under 2 s of |command| above
  // min_excitation_rad_s), gains more than 20 % apart (larger / smaller),
  // a dead time at the search limit, gaps in the series.
  std::vector<std::string> warnings;
};

/// Knobs of identifyPlant().
struct IdentifyOptions {
  double max_dead_time_s = 0.3;           // dead-time search range [0, this], at most 1 s
  double nominal_saturation_rad_s = 5.0;  // saturation kept when the run never reaches one
  double min_excitation_rad_s = 0.2;      // |command| above this counts as exciting the wheel
  double max_gap_s = 0.1;                 // a longer interval between samples splits the series
};

/// The data cannot give a model; what() says why (names the wheel).
class IdentifyError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Fits both wheels (method above). Throws IdentifyError naming the wheel and
/// the reason: series of different lengths, fewer than 50 samples (in total
/// or left between gaps), a non-finite value, time not strictly increasing,
/// no excitation (command never above min_excitation_rad_s), a speed that
/// never changes, a speed moving against the command; and for bad options.
PlantFit identifyPlant(const WheelSeries& left, const WheelSeries& right, const IdentifyOptions& options = {});

/// Wheel signals of a recorded run.
struct RunWheelData {
  WheelSeries left, right;             // t_s from the first message's robot_time_us
  std::size_t telemetry_messages = 0;  // /telemetry messages in the file
  std::size_t samples_used = 0;        // those kept: finite, robot time later than the previous kept one
};

/// Reads /telemetry (inspect.v1.Telemetry: robot_time_us, cmd_wheel_*_rad_s,
/// wheel_*_rad_s) of a run's MCAP file. Throws std::runtime_error naming the
/// file and the problem: not readable or not MCAP, no /telemetry channel, not
/// protobuf, a message that does not parse, no messages.
RunWheelData readRunWheelSeries(const std::string& mcap_path);

/// A commented YAML plant file (top-level `plant:` as in a world file, plus
/// `source:` and a `fit:` section) that loadPlantFile() reads back.
std::string plantYaml(const PlantFit& fit, const std::string& source);

/// Reads a plant file: `plant.left` and `plant.right`, each with gain,
/// time_constant_s, dead_time_s and saturation_rad_s (all required, ranges of
/// control::validatePlant); `source` and `fit` are optional. Throws
/// config::ConfigError naming the file and the key (unknown keys too).
control::PlantModel loadPlantFile(const std::string& path);

}  // namespace inspect::tuning
