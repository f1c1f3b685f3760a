#pragma once
// Fuzzy speed strategy (paper section 3.2.3, Table 1, Eq 9): from the
// distance to a person, the person's speed and the behaviour pattern, a
// zero-order Sugeno system (config/fuzzy/speed_strategy.fis) gives the speed
// reduction dV in [0, 1]; the commanded speed is v_hat = (1 - dV) v.
// docs/speed-strategy.md describes the rule base and its two safety properties.
#include <string>

#include "shared/behavior/behavior_pattern.hpp"
#include "shared/fuzzy/engine.hpp"

namespace inspect::behavior {

/// The distances that scale the fuzzy system's distance input.
struct SpeedStrategyParams {
  /// Maximum avoidance distance (term DF); the .fis distance input is
  /// distance_m / max_avoidance_m. Paper: human avoidance range 1.5-3.0 m.
  double max_avoidance_m = 3.0;
  /// Sensitive human distance (term DS): at or inside it the robot stops.
  /// 1.2 m = end of Hall's personal distance; the shipped .fis stops up to
  /// 0.4 max_avoidance_m, so this may not exceed 0.4 * max_avoidance_m there.
  double sensitive_m = 1.2;
};

/// Checks 0 < sensitive_m < max_avoidance_m, both finite; throws config::ConfigError.
void validate(const SpeedStrategyParams& params);

/// Evaluates Eq 9's speed factor 1 - dV. Copyable; one instance per thread.
class SpeedStrategy {
 public:
  /// Throws fuzzy::FisError when `fis` lacks the speed-strategy shape (Sugeno
  /// wtaver; inputs distance/speed/pattern with 4/2/4 terms, pattern term k at
  /// k; one output of constants in [0, 1]; a rule for each of the 32 term
  /// combinations; DS rules stop), and config::ConfigError when the params
  /// are invalid or sensitive_m lies outside the file's stop zone.
  SpeedStrategy(const fuzzy::Fis& fis, const SpeedStrategyParams& params);

  /// Speed factor 1 - dV in [0, 1] (Eq 9: v_hat = factor * v). kNone or a
  /// distance at or beyond max_avoidance_m -> 1; at or inside sensitive_m ->
  /// 0; a non-finite distance or speed, an unknown pattern or a failed
  /// evaluation -> 0 (stop). The speed's sign is ignored. Never allocates.
  double speedFactor(double distance_m, double human_speed_m_s, Pattern pattern) noexcept;

  /// dV of the last speedFactor() call (1 - factor).
  double lastDv() const { return last_dv_; }
  const SpeedStrategyParams& params() const { return params_; }
  const fuzzy::Engine& engine() const { return engine_; }

 private:
  fuzzy::Engine engine_;
  SpeedStrategyParams params_;
  double last_dv_ = 0.0;
};

/// Reads a .fis file and builds the strategy. Throws fuzzy::FisError
/// "path: reason" (unreadable, malformed or wrong shape) or config::ConfigError.
SpeedStrategy loadSpeedStrategy(const std::string& fis_path, const SpeedStrategyParams& params = {});

}  // namespace inspect::behavior
