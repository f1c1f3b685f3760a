#pragma once
// Test helpers: child processes with output to files, temp dirs, file polling.
// Every wait is bounded in time.
#include <sys/types.h>

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace inspect::test {

/// A child process; killed (SIGKILL) and reaped on destruction if still running.
class Process {
 public:
  Process() = default;
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;
  Process(Process&& o) noexcept;
  Process& operator=(Process&& o) noexcept;
  ~Process();

  /// Starts argv[0] with stdout/stderr appended to the given files and stdin
  /// from `stdin_path` (default /dev/null).
  static Process spawn(const std::vector<std::string>& argv, const std::string& stdout_path,
                       const std::string& stderr_path, const std::string& stdin_path = "/dev/null");
  /// As spawn, for a small test tool that stands in for hardware (the
  /// serial wire's relay): its main thread runs SCHED_FIFO at
  /// kHardwarePriority with SCHED_RESET_ON_FORK from the start. Without the
  /// privilege (not root, no CAP_SYS_NICE / RLIMIT_RTPRIO) it runs at normal
  /// priority and its stderr file says so. The project's own loops make
  /// themselves real-time once started (mcu_sim --realtime-priority,
  /// robot_client's realtime_priority), not through this.
  static Process spawnRealtime(const std::vector<std::string>& argv, const std::string& stdout_path,
                               const std::string& stderr_path);
  /// Above robot_client's loop (10, config/client.yaml): the simulated MCU and
  /// the wire are chips and cables of their own on a real robot, never
  /// starved by the Pi's processes.
  static constexpr int kHardwarePriority = 20;

  pid_t pid() const { return pid_; }
  bool running();
  void signal(int sig);
  /// Waits up to timeout_s for exit; returns the exit status (or 128+signal), nullopt on timeout.
  std::optional<int> wait(double timeout_s);
  /// SIGTERM, then SIGKILL after grace_s.
  void terminate(double grace_s = 3.0);

 private:
  static Process start(const std::vector<std::string>& argv, const std::string& stdout_path,
                       const std::string& stderr_path, const std::string& stdin_path, bool realtime);
  pid_t pid_ = -1;
  std::optional<int> status_;
};

/// A fresh directory under $TMPDIR, removed on destruction unless KEEP_TEST_DIRS is set.
class TempDir {
 public:
  explicit TempDir(const std::string& tag);
  ~TempDir();
  const std::string& path() const { return path_; }
  std::string operator/(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

std::string readFile(const std::string& path);
void writeFile(const std::string& path, const std::string& text);
bool exists(const std::string& path);
/// Polls `pred` every 10 ms until it holds or timeout_s passes.
bool waitUntil(const std::function<bool()>& pred, double timeout_s);
/// Monotonic clock, ns (the same clock mcu_sim writes in its truth log).
int64_t nowNs();
void sleepS(double s);

}  // namespace inspect::test
