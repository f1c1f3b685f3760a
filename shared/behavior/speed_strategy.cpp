#include "shared/behavior/speed_strategy.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <sstream>

#include "shared/config/config_node.hpp"
#include "shared/fuzzy/fis_error.hpp"
#include "shared/fuzzy/fis_reader.hpp"
#include "shared/util/number_text.hpp"

namespace inspect::behavior {
namespace {

constexpr std::size_t kDistance = 0, kSpeed = 1, kPattern = 2;
constexpr std::array<std::size_t, 3> kTermCounts{4, 2, 4};
// Points at which the stop zone [0, sensitive] is sampled when the strategy is built.
constexpr int kStopZoneSamples = 400;

std::string num(double v) { return util::significant(v, 6); }

[[noreturn]] void fisFail(const fuzzy::Fis& fis, const std::string& why) {
  throw fuzzy::FisError("fis '" + fis.name + "': speed strategy: " + why);
}

double membership(const fuzzy::MembershipFunction& mf, double x) { return fuzzy::mfValue(mf.type, mf.params, x); }

void checkShape(const fuzzy::Fis& fis) {
  fuzzy::checkComplete(fis);
  if (fis.type != fuzzy::FisType::kSugeno || fis.defuzz_method != fuzzy::DefuzzMethod::kWtaver)
    fisFail(fis, "must be a Sugeno system with DefuzzMethod 'wtaver' (Eq 9 is a weighted average)");
  if (fis.inputs.size() != 3 || fis.outputs.size() != 1)
    fisFail(fis, "must have 3 inputs (distance fraction, human speed, pattern) and 1 output (dV)");
  for (std::size_t i = 0; i < 3; ++i) {
    if (fis.inputs[i].mfs.size() != kTermCounts[i])
      fisFail(fis, "input " + std::to_string(i + 1) + " '" + fis.inputs[i].name + "' must have " +
                       std::to_string(kTermCounts[i]) + " terms, has " + std::to_string(fis.inputs[i].mfs.size()));
  }
  for (const auto& mf : fis.outputs[0].mfs) {
    if (mf.type != fuzzy::MfType::kConstant || !(mf.params[0] >= 0.0 && mf.params[0] <= 1.0))
      fisFail(fis, "output term '" + mf.name + "' must be a constant in [0, 1]");
  }
  // Pattern k (Pattern enum value) must select term k alone.
  const auto& pattern = fis.inputs[kPattern];
  for (std::size_t k = 0; k < 4; ++k) {
    for (std::size_t t = 0; t < 4; ++t) {
      const double mu = membership(pattern.mfs[t], static_cast<double>(k + 1));
      if (mu != (t == k ? 1.0 : 0.0))
        fisFail(fis, "pattern term '" + pattern.mfs[t].name + "' has membership " + num(mu) + " at pattern " +
                         std::to_string(k + 1) + " (term k must be 1 at k and 0 at the other patterns)");
    }
  }
  // Completeness: every (distance, speed, pattern) term combination has a rule.
  for (std::size_t d = 0; d < 4; ++d) {
    for (std::size_t s = 0; s < 2; ++s) {
      for (std::size_t p = 0; p < 4; ++p) {
        const std::array<std::size_t, 3> combo{d, s, p};
        const bool covered = std::any_of(fis.rules.begin(), fis.rules.end(), [&](const fuzzy::Rule& r) {
          if (r.connection != fuzzy::Connection::kAnd || !(r.weight > 0.0) || r.consequent[0] == 0) return false;
          for (std::size_t i = 0; i < 3; ++i) {
            const int a = r.antecedent[i];
            if (a != 0 && a != static_cast<int>(combo[i] + 1)) return false;
          }
          return true;
        });
        if (!covered)
          fisFail(fis, "no rule for " + fis.inputs[kDistance].mfs[d].name + " and " + fis.inputs[kSpeed].mfs[s].name +
                           " and " + pattern.mfs[p].name + " (the rule base must cover all 32 combinations)");
      }
    }
  }
}

// Every rule that can fire at a distance fraction in [0, x_stop] must command
// dV = 1, so the file stops wherever the wrapper's sensitive distance does and
// the speed does not jump at sensitive_m.
void checkStopZone(const fuzzy::Fis& fis, const SpeedStrategyParams& params) {
  const double x_stop = params.sensitive_m / params.max_avoidance_m;
  const auto& dist = fis.inputs[kDistance];
  for (std::size_t r = 0; r < fis.rules.size(); ++r) {
    const fuzzy::Rule& rule = fis.rules[r];
    const int c = rule.consequent[0];
    if (c == 0 || !(rule.weight > 0.0)) continue;
    if (fis.outputs[0].mfs[static_cast<std::size_t>(c - 1)].params[0] == 1.0) continue;
    const int a = rule.antecedent[kDistance];
    double worst_x = 0.0, worst_mu = 0.0;
    for (int k = 0; k <= kStopZoneSamples; ++k) {
      const double x = x_stop * k / kStopZoneSamples;
      double mu = 1.0;  // don't care (and OR rules: other inputs may fire them)
      if (a != 0 && rule.connection == fuzzy::Connection::kAnd) {
        mu = membership(dist.mfs[static_cast<std::size_t>(std::abs(a) - 1)], x);
        if (a < 0) mu = 1.0 - mu;
      }
      if (mu > worst_mu) {
        worst_mu = mu;
        worst_x = x;
      }
    }
    if (worst_mu > 0.0) {
      throw config::ConfigError("speed strategy: sensitive_m = " + num(params.sensitive_m) +
                                " m lies beyond the stop zone of fis '" + fis.name + "': rule " +
                                std::to_string(r + 1) + " (not a stop) fires with " + num(worst_mu) +
                                " at distance fraction " + num(worst_x) + " = " +
                                num(worst_x * params.max_avoidance_m) +
                                " m; lower sensitive_m or move the distance terms in the file");
    }
  }
}

}  // namespace

void validate(const SpeedStrategyParams& params) {
  if (!std::isfinite(params.max_avoidance_m) || !(params.max_avoidance_m > 0.0))
    throw config::ConfigError("speed strategy: max_avoidance_m must be finite and > 0, got " +
                              num(params.max_avoidance_m));
  if (!std::isfinite(params.sensitive_m) || !(params.sensitive_m > 0.0) ||
      !(params.sensitive_m < params.max_avoidance_m))
    throw config::ConfigError("speed strategy: sensitive_m must lie in (0, max_avoidance_m = " +
                              num(params.max_avoidance_m) + ") m, got " + num(params.sensitive_m));
}

SpeedStrategy::SpeedStrategy(const fuzzy::Fis& fis, const SpeedStrategyParams& params)
    : engine_((checkShape(fis), fis)), params_(params) {  // shape checked before the engine is built
  validate(params_);
  checkStopZone(engine_.fis(), params_);
}

double SpeedStrategy::speedFactor(double distance_m, double human_speed_m_s, Pattern pattern) noexcept {
  double dv = 1.0;  // stop unless shown otherwise
  switch (pattern) {
    case Pattern::kNone:
      dv = 0.0;
      break;
    case Pattern::kCrossing:
    case Pattern::kEncountering:
    case Pattern::kLeading:
    case Pattern::kConfronting:
      if (!std::isfinite(distance_m) || !std::isfinite(human_speed_m_s)) break;
      if (distance_m >= params_.max_avoidance_m) {
        dv = 0.0;  // no control signal outside the avoidance distance (section 3.2.3)
      } else if (distance_m > params_.sensitive_m) {
        const std::array<double, 3> in{distance_m / params_.max_avoidance_m, std::abs(human_speed_m_s),
                                       static_cast<double>(pattern)};
        std::array<double, 1> out{};
        if (engine_.evaluate(in, out) == fuzzy::EvalStatus::kOk && std::isfinite(out[0]))
          dv = std::clamp(out[0], 0.0, 1.0);
      }
      break;
  }
  last_dv_ = dv;
  return 1.0 - dv;  // Eq 9: v_hat = (1 - dV) v
}

SpeedStrategy loadSpeedStrategy(const std::string& fis_path, const SpeedStrategyParams& params) {
  const fuzzy::Fis fis = fuzzy::readFisFile(fis_path);  // FisError "path:line: reason"
  try {
    return SpeedStrategy(fis, params);
  } catch (const fuzzy::FisError& e) {
    throw fuzzy::FisError(fis_path + ": " + e.what());
  } catch (const config::ConfigError& e) {
    throw config::ConfigError(fis_path + ": " + e.what());
  }
}

}  // namespace inspect::behavior
