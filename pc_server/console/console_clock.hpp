#pragma once
// The console's time: the clock it reads (deadlines of `wait`, `expect ...
// within` and Acks; the registry's snapshot ages) and the way it waits.
// pc_server runs it on CLOCK_MONOTONIC with sleeps that a stop request
// interrupts; the console's tests run it on a clock they advance themselves
// (tests/pc_server/manual_clock.hpp), so that `wait 10` takes no time and an
// expect's timeout is exact, on any machine.
#include <cstdint>

#include "pc_server/app/stop_flag.hpp"
#include "shared/util/clock.hpp"

namespace inspect::server {

class ConsoleClock {
 public:
  virtual ~ConsoleClock() = default;
  /// Monotonic nanoseconds: the time base of the registry (RobotRegistry::snapshot).
  virtual int64_t nowNs() = 0;
  /// Waits `seconds`, or less when the stop is requested; false when it was.
  virtual bool sleep(double seconds) = 0;
};

/// The real clock: CLOCK_MONOTONIC, sleeps that StopFlag::request() ends.
class SteadyConsoleClock final : public ConsoleClock {
 public:
  explicit SteadyConsoleClock(StopFlag& stop) : stop_(stop) {}
  int64_t nowNs() override { return monoNowNs(); }
  bool sleep(double seconds) override { return stop_.sleepFor(steadyDuration(seconds)); }

 private:
  StopFlag& stop_;
};

}  // namespace inspect::server
