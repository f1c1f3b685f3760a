#pragma once
// A one-shot "shut down" request shared by the signal handler, the console and
// waits: sleeping threads wake at once, and a pipe lets poll() loops wake too.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <vector>

#include "pc_server/link/wake_signal.hpp"

namespace inspect::server {

/// Set once (SIGINT/SIGTERM, quit); never reset.
class StopFlag {
 public:
  StopFlag();
  ~StopFlag();
  StopFlag(const StopFlag&) = delete;
  StopFlag& operator=(const StopFlag&) = delete;

  /// Requests the stop; thread-safe, idempotent.
  void request();
  bool requested() const { return requested_.load(); }
  /// Sleeps for `d` or until the stop request; false if stopped.
  bool sleepFor(std::chrono::steady_clock::duration d);
  /// Blocks until the stop request.
  void wait();
  /// While set, an interrupt (Ctrl-C) sets *target instead of stopping the
  /// server: a long console job (tune) is cancelled and keeps its result.
  /// nullptr clears it.
  void setInterruptTarget(std::atomic<bool>* target) { interrupt_target_.store(target); }
  /// SIGINT: true when an interrupt target took it (the server goes on).
  bool interrupt() {
    std::atomic<bool>* t = interrupt_target_.load();
    if (!t) return false;
    t->store(true);
    return true;
  }
  /// Waits on `signal` (WakeSignal::waitChange from generation `seen`, at
  /// most `timeout`) that request() also ends: false when the stop was requested.
  bool waitChange(WakeSignal& signal, uint64_t seen, std::chrono::steady_clock::duration timeout);
  /// A descriptor that becomes readable once the stop is requested (for poll()).
  int wakeFd() const { return pipe_[0]; }

 private:
  std::atomic<bool> requested_{false};
  std::atomic<std::atomic<bool>*> interrupt_target_{nullptr};
  std::mutex mu_;
  std::condition_variable cv_;
  std::vector<WakeSignal*> waiting_;  // signals being waited on in waitChange (mu_)
  int pipe_[2] = {-1, -1};
};

}  // namespace inspect::server
