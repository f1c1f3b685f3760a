#pragma once
// The paper's gains of a tuning setup (its config/control.yaml), the
// tuning tests' starting point.
#include "pc_server/tuning/tuner.hpp"
#include "shared/control/gain_set.hpp"

namespace inspect::test {

inline control::GainSet paperGains(const tuning::TuneSetup& s) {
  control::GainSet g;
  g.fuzzy = s.control.tracker.fuzzy;
  g.aux = s.control.tracker.aux;
  return g;
}

}  // namespace inspect::test
