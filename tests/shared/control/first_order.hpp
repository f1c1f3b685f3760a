#pragma once
// A first-order plant for controller tests: the exact discretisation of
// tau y' = u - y (the simulator's hub motor without dead time).
#include <cmath>

namespace inspect::test {

struct FirstOrder {
  double tau_s;
  double y = 0;
  void step(double u, double dt_s) {
    const double a = std::exp(-dt_s / tau_s);
    y = a * y + (1 - a) * u;
  }
};

}  // namespace inspect::test
