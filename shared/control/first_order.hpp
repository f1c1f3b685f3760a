#pragma once
// The exact step of a first-order lag, tau * w' = target - w, over dt: the
// speed at its end and its integral over it (so a wheel's travel is exact
// whatever the step size). Header-only and free of the heap: the simulator's
// motors (sim/robot_plant) and the QEMU board's encoder model
// (shared/hil/encoder_model.hpp, in the firmware image) step the same lag.
#include <cmath>

namespace inspect::control {

template <class T>
struct FirstOrderStep {
  T value;     // at the end of the step
  T integral;  // over the step
};

/// tau > 0, in the same unit of time as dt.
template <class T>
FirstOrderStep<T> firstOrderStep(T w0, T target, T tau, T dt) {
  const T decay = std::exp(-dt / tau);
  return {target + (w0 - target) * decay, target * dt + (w0 - target) * tau * (T(1) - decay)};
}

}  // namespace inspect::control
