#pragma once
// A console clock that only moves when the console waits: each sleep
// advances it by exactly the time asked for and runs what a test scheduled
// for that moment (a telemetry message, an Ack), so console tests take no
// real time and their timings are exact.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>

#include "pc_server/console/console_clock.hpp"
#include "pc_server/operator/stop_flag.hpp"
#include "shared/util/clock.hpp"

namespace inspect::test {

class ManualClock final : public server::ConsoleClock {
 public:
  explicit ManualClock(server::StopFlag& stop) : stop_(stop), start_ns_(monoNowNs()), now_ns_(start_ns_) {}

  int64_t nowNs() override { return now_ns_.load(); }
  bool sleep(double seconds) override { return advance(seconds, [] { return false; }); }
  /// As sleep(), but returns at the first scheduled event after which `signal`
  /// has moved past `seen` (the clock then stands at that event's time).
  bool waitSignal(double seconds, server::WakeSignal& signal, uint64_t seen) override {
    return advance(seconds, [&] { return signal.generation() != seen; });
  }

  /// Runs `fn` when the clock passes `after_s` from now.
  void at(double after_s, std::function<void()> fn) {
    due_.emplace(now_ns_.load() + std::llround(after_s * 1e9), std::move(fn));
  }
  /// Seconds since the clock was made.
  double elapsedS() const { return static_cast<double>(now_ns_.load() - start_ns_) * 1e-9; }
  /// Calls of sleep() that waited.
  int sleeps() const { return sleeps_; }

 private:
  // Moves the clock on by `seconds`, running what falls due on the way at its
  // own time, in order; stops early after an event once `woken()` holds.
  bool advance(double seconds, const std::function<bool()>& woken) {
    if (stop_.requested()) return false;
    ++sleeps_;
    // At least a nanosecond: a wait always moves the clock on, as a real one would.
    const int64_t until = now_ns_.load() + std::max<int64_t>(1, std::llround(seconds * 1e9));
    while (!due_.empty() && due_.begin()->first <= until) {
      auto next = due_.extract(due_.begin());
      now_ns_.store(next.key());
      next.mapped()();
      if (stop_.requested()) return false;  // a stop ends the sleep then, as StopFlag::sleepFor does
      if (woken()) return true;
    }
    now_ns_.store(until);
    return !stop_.requested();
  }

  server::StopFlag& stop_;
  const int64_t start_ns_;
  std::atomic<int64_t> now_ns_;
  std::multimap<int64_t, std::function<void()>> due_;
  int sleeps_ = 0;
};

}  // namespace inspect::test
