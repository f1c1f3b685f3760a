#pragma once
// The console's time: the clock it reads (deadlines of `wait`, `expect ...
// within` and Acks; the registry's snapshot ages) and the way it waits.
// pc_server runs it on CLOCK_MONOTONIC with sleeps that a stop request
// interrupts; the console's tests run it on a clock they advance themselves
// (tests/pc_server/console/manual_clock.hpp), so that `wait 10` takes no time and an
// expect's timeout is exact, on any machine. Acks are waited for on the
// registry's WakeSignal: the console wakes when one arrives, not by polling.
#include <cstdint>

#include "pc_server/operator/stop_flag.hpp"
#include "pc_server/link/wake_signal.hpp"
#include "shared/util/clock.hpp"

namespace inspect::server {

class ConsoleClock {
 public:
  virtual ~ConsoleClock() = default;
  /// Monotonic nanoseconds: the time base of the registry (RobotRegistry::snapshot).
  virtual int64_t nowNs() = 0;
  /// Waits `seconds`, or less when the stop is requested; false when it was.
  virtual bool sleep(double seconds) = 0;
  /// Waits at most `seconds` for `signal` to move past generation `seen`
  /// (returns early when it does); false when the stop was requested.
  virtual bool waitSignal(double seconds, WakeSignal& signal, uint64_t seen) = 0;
};

/// The real clock: CLOCK_MONOTONIC, sleeps that StopFlag::request() ends.
class SteadyConsoleClock final : public ConsoleClock {
 public:
  explicit SteadyConsoleClock(StopFlag& stop) : stop_(stop) {}
  int64_t nowNs() override { return monoNowNs(); }
  bool sleep(double seconds) override { return stop_.sleepFor(steadyDuration(seconds)); }
  bool waitSignal(double seconds, WakeSignal& signal, uint64_t seen) override {
    return stop_.waitChange(signal, seen, steadyDuration(seconds));  // a stop request ends it at once
  }

 private:
  StopFlag& stop_;
};

}  // namespace inspect::server
