#pragma once
// The tunable gains of trajectory tracking as one unit: the fuzzy-PID's
// base gains and scalings (Eq 15: kp', ki', kd', ke, kec, k1, k2, k3) and the
// auxiliary kinematic controller's gains (Eq 12: a1, a2, a3). This is what
// `gains set/push` edits, the tuner optimises, the robot validates and applies
// at a tick boundary, and runs record. Bounds are those of config/control.yaml.
#include <array>
#include <cmath>
#include <cstdio>
#include <string>

#include "shared/control/fuzzy_pid.hpp"
#include "shared/control/tracking_controller.hpp"

namespace inspect::control {

struct GainSet {
  FuzzyPidParams fuzzy;  // .base = kp', ki', kd'
  AuxiliaryGains aux;
};

/// The eleven named gains in a fixed order (also the order of GainSet's
/// YAML file and of the tuner's parameter vector).
inline constexpr std::array<const char*, 11> kGainNames = {"kp", "ki", "kd", "ke", "kec", "k1",
                                                           "k2", "k3", "a1", "a2", "a3"};

/// Pointer to the named gain inside `g`, or nullptr for an unknown name.
inline double* gainByName(GainSet& g, const std::string& name) {
  if (name == "kp") return &g.fuzzy.base.kp;
  if (name == "ki") return &g.fuzzy.base.ki;
  if (name == "kd") return &g.fuzzy.base.kd;
  if (name == "ke") return &g.fuzzy.ke;
  if (name == "kec") return &g.fuzzy.kec;
  if (name == "k1") return &g.fuzzy.k1;
  if (name == "k2") return &g.fuzzy.k2;
  if (name == "k3") return &g.fuzzy.k3;
  if (name == "a1") return &g.aux.a1;
  if (name == "a2") return &g.aux.a2;
  if (name == "a3") return &g.aux.a3;
  return nullptr;
}
inline double gainValue(const GainSet& g, const std::string& name) {
  GainSet copy = g;
  const double* p = gainByName(copy, name);
  return p ? *p : std::nan("");
}

/// Allowed range of a gain (config/control.yaml): kp..k3 in [0, 100], a1..a3 in [-20, 0].
inline void gainBounds(const std::string& name, double& lo, double& hi) {
  const bool aux = name == "a1" || name == "a2" || name == "a3";
  lo = aux ? -20.0 : 0.0;
  hi = aux ? 0.0 : 100.0;
}

/// "" when every gain is finite and within its bounds, else the first problem
/// ("kp = nan is not finite", "a2 = 3 is outside [-20, 0]").
inline std::string validateGains(const GainSet& g) {
  for (const char* name : kGainNames) {
    const double v = gainValue(g, name);
    char buf[128];
    if (!std::isfinite(v)) {
      std::snprintf(buf, sizeof buf, "%s = %g is not finite", name, v);
      return buf;
    }
    double lo = 0, hi = 0;
    gainBounds(name, lo, hi);
    if (v < lo || v > hi) {
      std::snprintf(buf, sizeof buf, "%s = %g is outside [%g, %g]", name, v, lo, hi);
      return buf;
    }
  }
  return "";
}

inline bool sameGains(const GainSet& a, const GainSet& b) {
  for (const char* name : kGainNames)
    if (gainValue(a, name) != gainValue(b, name)) return false;
  return true;
}

}  // namespace inspect::control
