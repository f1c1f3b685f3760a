#include "pc_server/operator/stop_flag.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>

namespace inspect::server {

StopFlag::StopFlag() {
  if (::pipe2(pipe_, O_CLOEXEC | O_NONBLOCK) != 0) pipe_[0] = pipe_[1] = -1;
}

StopFlag::~StopFlag() {
  for (int fd : pipe_)
    if (fd >= 0) ::close(fd);
}

void StopFlag::request() {
  {
    std::lock_guard lk(mu_);
    if (requested_.exchange(true)) return;
  }
  cv_.notify_all();
  std::vector<WakeSignal*> waiting;
  {
    std::lock_guard lk(mu_);
    waiting = waiting_;
  }
  for (WakeSignal* s : waiting) s->notify();
  if (pipe_[1] >= 0) {
    const char b = 1;
    [[maybe_unused]] const auto n = ::write(pipe_[1], &b, 1);
  }
}

bool StopFlag::sleepFor(std::chrono::steady_clock::duration d) {
  std::unique_lock lk(mu_);
  return !cv_.wait_for(lk, d, [this] { return requested_.load(); });
}

bool StopFlag::waitChange(WakeSignal& signal, uint64_t seen, std::chrono::steady_clock::duration timeout) {
  {
    std::lock_guard lk(mu_);
    waiting_.push_back(&signal);
  }
  // Registered before the look: a request() from here on notifies `signal`.
  if (!requested_.load()) signal.waitChange(seen, timeout);
  {
    std::lock_guard lk(mu_);
    waiting_.erase(std::find(waiting_.begin(), waiting_.end(), &signal));
  }
  return !requested_.load();
}

void StopFlag::wait() {
  std::unique_lock lk(mu_);
  cv_.wait(lk, [this] { return requested_.load(); });
}

}  // namespace inspect::server
