#include "pc_server/recording/run_copier.hpp"

#include <chrono>
#include <filesystem>

namespace inspect::server {

namespace fs = std::filesystem;

namespace {

// Copies the directory; the bytes of its files. Throws fs::filesystem_error.
int64_t copyDir(const std::string& src, const std::string& dst) {
  const std::string partial = dst + ".partial";
  fs::remove_all(partial);
  fs::create_directories(fs::path(partial).parent_path());
  fs::copy(src, partial, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  int64_t bytes = 0;
  for (const auto& e : fs::recursive_directory_iterator(partial))
    if (e.is_regular_file()) bytes += static_cast<int64_t>(e.file_size());
  fs::remove_all(dst);
  fs::rename(partial, dst);
  return bytes;
}

}  // namespace

RunCopier::RunCopier(Done done) : done_(std::move(done)), thread_([this] { loop(); }) {}

RunCopier::~RunCopier() {
  {
    std::lock_guard lk(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void RunCopier::copy(const std::string& run_id, const std::string& src, const std::string& dst) {
  {
    std::lock_guard lk(mu_);
    jobs_.push_back({run_id, src, dst});
  }
  cv_.notify_all();
}

bool RunCopier::waitIdle(double timeout_s) {
  std::unique_lock lk(mu_);
  return cv_.wait_for(lk, std::chrono::duration<double>(timeout_s), [&] { return jobs_.empty() && !busy_; });
}

void RunCopier::loop() {
  for (;;) {
    Job job;
    {
      std::unique_lock lk(mu_);
      cv_.wait(lk, [&] { return stop_ || !jobs_.empty(); });
      if (stop_) return;
      job = std::move(jobs_.front());
      jobs_.pop_front();
      busy_ = true;
    }
    int64_t bytes = 0;
    std::string error;
    try {
      bytes = copyDir(job.src, job.dst);
    } catch (const std::exception& e) {
      error = e.what();
    }
    if (done_) done_(job.run_id, job.dst, bytes, error);
    {
      std::lock_guard lk(mu_);
      busy_ = false;
    }
    cv_.notify_all();
  }
}

}  // namespace inspect::server
