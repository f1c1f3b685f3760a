#pragma once
// Copies ended runs to the fleet's shared runs root (recording.shared_runs,
// docs/recording.md "A shared runs root") on a thread of its own: a run's
// MCAP and MP4 are hundreds of MB an hour, not to be copied on the link's
// thread. A copy goes to <dst>.partial and is renamed when whole, so a
// reader never sees half a run.
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace inspect::server {

class RunCopier {
 public:
  /// Called on the copier's thread after each copy: the bytes copied, or why not ("" = copied).
  using Done = std::function<void(const std::string& run_id, const std::string& dst, int64_t bytes,
                                  const std::string& error)>;
  explicit RunCopier(Done done);
  /// Finishes the copy under way; the queued ones are left (the next start
  /// queues every run without a shared copy again).
  ~RunCopier();
  RunCopier(const RunCopier&) = delete;
  RunCopier& operator=(const RunCopier&) = delete;

  /// Queues the copy of directory `src` to `dst` (replaced if it exists).
  void copy(const std::string& run_id, const std::string& src, const std::string& dst);
  /// Waits until every queued copy is done, at most `timeout_s`; false if not.
  bool waitIdle(double timeout_s);

 private:
  struct Job {
    std::string run_id, src, dst;
  };
  void loop();

  Done done_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<Job> jobs_;
  bool busy_ = false, stop_ = false;
  std::thread thread_;
};

}  // namespace inspect::server
