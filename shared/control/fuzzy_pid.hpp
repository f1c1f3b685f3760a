#pragma once
// Fuzzy self-tuning PID (paper Eq 15): a fuzzy system with inputs e and ec
// (error and its rate, scaled by ke and kec into [-3, 3]) gives kpx, kix, kdx;
// the PID of Eq 14 then runs with kp = kp' + k1 kpx, ki = ki' + k2 kix,
// kd = kd' + k3 kdx. The fuzzy system is config/fuzzy/fuzzy_pid.fis.
#include <memory>
#include <optional>

#include "shared/control/pid_controller.hpp"
#include "shared/fuzzy/engine.hpp"
#include "shared/fuzzy/lookup_surface.hpp"

namespace inspect::control {

/// The paper's fuzzy-PID settings.
struct FuzzyPidParams {
  PidGains base{9.0, 2.0, 3.0};  // kp', ki', kd'
  double ke = 0.9;               // error scaling into the fuzzy universe
  double kec = 0.1;              // error-rate scaling
  double k1 = 3.0;               // kpx scaling
  double k2 = 1.0;               // kix scaling
  double k3 = 1.0;               // kdx scaling
};

/// Evaluates the gain-scheduling fuzzy system, directly or through a
/// compiled lookup surface. Checks the system has 2 inputs and 3 outputs.
class FuzzyGainScheduler {
 public:
  /// Throws fuzzy::FisError if the system does not have the fuzzy-PID shape.
  FuzzyGainScheduler(const fuzzy::Fis& fis, bool use_lookup);

  /// Eq 15. e and ec are raw (wheel-speed error in rad/s and its rate in
  /// rad/s^2); they are scaled by ke/kec and saturated at the input ranges.
  /// Gains never go negative. Never allocates.
  PidGains gains(const FuzzyPidParams& p, double e, double ec) noexcept;

  /// The fuzzy outputs (kpx, kix, kdx) of the last call.
  const double* lastOutputs() const { return out_; }
  bool usesLookup() const { return lookup_ != nullptr; }

 private:
  std::unique_ptr<fuzzy::Engine> engine_;
  std::unique_ptr<fuzzy::LookupSurface> lookup_;
  double in_min_[2] = {-3, -3}, in_max_[2] = {3, 3};
  double out_[3] = {0, 0, 0};
};

/// State of one fuzzy-PID loop.
struct FuzzyPidState {
  PidState pid;
  double prev_error = 0.0;
  bool primed = false;
  PidGains gains;  // gains used in the last step
};

/// One fuzzy-PID step: schedules the gains from e and ec, then runs Eq 14.
double fuzzyPidStep(FuzzyGainScheduler& sched, const FuzzyPidParams& p, const PidConfig& cfg, FuzzyPidState& s,
                    double setpoint, double measurement, double dt_s);

}  // namespace inspect::control
