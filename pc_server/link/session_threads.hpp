#pragma once
// The robot sessions' threads: one io_context per thread, each session on
// one of them for its whole life (round robin at accept). A shared
// io_context run by several threads hands every batch of ready sockets from
// the thread in epoll_wait to the others through a condition variable, and
// a session's handlers hop between threads; at 100 robots that was a fifth
// of the server's CPU in futex and scheduler time (docs/load.md). Here the
// thread that waits for a socket runs its handlers, and nothing else wakes.
// A thread runs everything ready, then sleeps kBatch before it waits again:
// one wake-up then takes the frames of several robots (about 5 at 100
// robots at 100 Hz) instead of one, for at most kBatch more latency (the
// median 0.13 -> 0.7-1.0 ms; heartbeats every 50 ms, the robot's link
// timeout 250 ms).
#include <pthread.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>

namespace inspect::server {

class SessionThreads {
 public:
  static constexpr std::chrono::microseconds kBatch{1000};

  explicit SessionThreads(std::size_t threads) {
    for (std::size_t i = 0; i < std::max<std::size_t>(threads, 1); ++i) {
      auto& c = contexts_.emplace_back(std::make_unique<Context>());
      c->work.emplace(c->ioc.get_executor());
    }
  }
  ~SessionThreads() { stop(); }
  SessionThreads(const SessionThreads&) = delete;
  SessionThreads& operator=(const SessionThreads&) = delete;

  /// Starts one thread per io_context (once), named link0, link1, ... (top -H).
  void start() {
    for (std::size_t i = 0; i < contexts_.size(); ++i)
      if (auto& c = contexts_[i]; !c->thread.joinable()) c->thread = std::thread([ctx = c.get(), i] {
        pthread_setname_np(pthread_self(), ("link" + std::to_string(i)).c_str());
        for (;;) {
          if (ctx->ioc.run_one() == 0) return;  // stopped
          ctx->ioc.poll();
          if (ctx->ioc.stopped()) return;
          std::this_thread::sleep_for(kBatch);  // let more frames arrive: one wake-up for several
        }
      });
  }
  /// Stops the io_contexts and joins their threads; handlers not yet run are dropped. Idempotent.
  void stop() {
    for (auto& c : contexts_) {
      c->work.reset();
      c->ioc.stop();
    }
    for (auto& c : contexts_)
      if (c->thread.joinable()) c->thread.join();
  }
  /// The io_context for the next session (round robin; any thread).
  boost::asio::io_context& next() { return contexts_[next_.fetch_add(1) % contexts_.size()]->ioc; }
  std::size_t size() const { return contexts_.size(); }

 private:
  struct Context {
    boost::asio::io_context ioc{1};  // one thread: Asio may skip its internal locking
    std::optional<boost::asio::executor_work_guard<boost::asio::io_context::executor_type>> work;
    std::thread thread;
  };
  std::vector<std::unique_ptr<Context>> contexts_;
  std::atomic<std::size_t> next_{0};
};

}  // namespace inspect::server
