#pragma once
// "Something arrived": a generation counter with a condition variable. The
// registry bumps it for every Ack; a console waiting for one reads the
// generation, checks the registry, and sleeps until the generation moves (or
// its time runs out): woken at once, no polling, no lost wake-up.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>

namespace inspect::server {

class WakeSignal {
 public:
  /// Thread-safe; wakes every waiter.
  void notify() {
    {
      std::lock_guard lk(mu_);
      ++generation_;
    }
    cv_.notify_all();
  }
  uint64_t generation() const {
    std::lock_guard lk(mu_);
    return generation_;
  }
  /// Waits until the generation differs from `seen` or `timeout` passes; true when it moved.
  bool waitChange(uint64_t seen, std::chrono::steady_clock::duration timeout) {
    std::unique_lock lk(mu_);
    return cv_.wait_for(lk, timeout, [&] { return generation_ != seen; });
  }

 private:
  mutable std::mutex mu_;
  std::condition_variable cv_;
  uint64_t generation_ = 0;
};

}  // namespace inspect::server
