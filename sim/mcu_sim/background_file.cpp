#include "sim/mcu_sim/background_file.hpp"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>

#include "shared/util/clock.hpp"

namespace inspect::sim {

BackgroundFile::BackgroundFile(const std::string& path, std::string_view what, int period_ms)
    : file_(std::fopen(path.c_str(), "w")), period_ms_(std::max(1, period_ms)) {
  if (!file_)
    throw std::runtime_error(std::string(what) + " " + path + ": cannot open for writing: " + std::strerror(errno));
  thread_ = std::thread([this] { run(); });
}

BackgroundFile::~BackgroundFile() {
  {
    std::lock_guard lk(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  std::fclose(file_);
}

void BackgroundFile::append(std::string_view text) {
  {
    std::lock_guard lk(mu_);
    appended_ += text.size();
    if (pending_.size() + text.size() > kMaxBuffered) {
      dropped_ += text.size();
      return;
    }
    pending_.append(text);
  }
}

void BackgroundFile::sync() {
  std::unique_lock lk(mu_);
  const uint64_t target = appended_;
  sync_wanted_ = true;
  cv_.notify_all();
  written_.wait(lk, [&] { return written_upto_ >= target || stop_; });
}

uint64_t BackgroundFile::droppedBytes() const {
  std::lock_guard lk(mu_);
  return dropped_;
}

double BackgroundFile::maxWriteMs() const {
  std::lock_guard lk(mu_);
  return max_write_ms_;
}

void BackgroundFile::run() {
  // Not real-time: the thread inherits the creator's policy, and a writer
  // waiting on the disk must never compete with the simulated MCU.
  sched_param sp{};
  pthread_setschedparam(pthread_self(), SCHED_OTHER, &sp);
  std::string out;
  for (;;) {
    uint64_t upto = 0;
    bool stopping = false;
    {
      std::unique_lock lk(mu_);
      cv_.wait_for(lk, std::chrono::milliseconds(period_ms_), [&] { return stop_ || sync_wanted_; });
      out.clear();
      out.swap(pending_);
      upto = appended_;
      sync_wanted_ = false;
      stopping = stop_;
    }
    double ms = 0.0;
    if (!out.empty()) {
      const int64_t t0 = monoNowNs();
      std::fwrite(out.data(), 1, out.size(), file_);
      std::fflush(file_);
      ms = static_cast<double>(monoNowNs() - t0) / 1e6;
    }
    {
      std::lock_guard lk(mu_);
      written_upto_ = upto;
      max_write_ms_ = std::max(max_write_ms_, ms);
    }
    written_.notify_all();
    if (stopping) return;
  }
}

}  // namespace inspect::sim
