#include "shared/control/fuzzy_pid.hpp"

#include <algorithm>
#include <cmath>

#include "shared/fuzzy/fis_error.hpp"

namespace inspect::control {

FuzzyGainScheduler::FuzzyGainScheduler(const fuzzy::Fis& fis, bool use_lookup) {
  if (fis.inputs.size() != 2 || fis.outputs.size() != 3)
    throw fuzzy::FisError("fuzzy-PID system '" + fis.name + "' must have 2 inputs (e, ec) and 3 outputs (kpx, kix, kdx)");
  for (int i = 0; i < 2; ++i) {
    in_min_[i] = fis.inputs[static_cast<std::size_t>(i)].min;
    in_max_[i] = fis.inputs[static_cast<std::size_t>(i)].max;
  }
  if (use_lookup)
    lookup_ = std::make_unique<fuzzy::LookupSurface>(fis);
  else
    engine_ = std::make_unique<fuzzy::Engine>(fis);
}

PidGains FuzzyGainScheduler::gains(const FuzzyPidParams& p, double e, double ec) noexcept {
  const double in[2] = {std::clamp(p.ke * e, in_min_[0], in_max_[0]), std::clamp(p.kec * ec, in_min_[1], in_max_[1])};
  const auto st = lookup_ ? lookup_->evaluate(in, out_) : engine_->evaluate(in, out_);
  if (st == fuzzy::EvalStatus::kNonFiniteInput || st == fuzzy::EvalStatus::kBadSize || !std::isfinite(out_[0]) ||
      !std::isfinite(out_[1]) || !std::isfinite(out_[2])) {
    out_[0] = out_[1] = out_[2] = 0.0;  // fall back to the base gains
  }
  // Eq 15.
  return {std::max(0.0, p.base.kp + p.k1 * out_[0]), std::max(0.0, p.base.ki + p.k2 * out_[1]),
          std::max(0.0, p.base.kd + p.k3 * out_[2])};
}

double fuzzyPidStep(FuzzyGainScheduler& sched, const FuzzyPidParams& p, const PidConfig& cfg, FuzzyPidState& s,
                    double setpoint, double measurement, double dt_s) {
  if (!std::isfinite(setpoint) || !std::isfinite(measurement) || !(dt_s > 0)) return s.pid.output;
  const double e = setpoint - measurement;
  const double ec = s.primed ? (e - s.prev_error) / dt_s : 0.0;
  s.prev_error = e;
  s.primed = true;
  s.gains = sched.gains(p, e, ec);
  return pidStep(cfg, s.gains, s.pid, setpoint, measurement, dt_s);
}

}  // namespace inspect::control
