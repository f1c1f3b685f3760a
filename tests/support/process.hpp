#pragma once
// Test helpers: child processes with output to files, temp dirs, file polling.
// Every wait is bounded in time.
#include <sys/types.h>

#include <functional>
#include <map>
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

  pid_t pid() const { return pid_; }
  bool running();
  void signal(int sig);
  /// Waits up to timeout_s for exit; returns the exit status (or 128+signal), nullopt on timeout.
  std::optional<int> wait(double timeout_s);
  /// SIGTERM, then SIGKILL after grace_s.
  void terminate(double grace_s = 3.0);

 private:
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
/// utime + stime (clock ticks, sysconf(_SC_CLK_TCK)) of every thread of
/// process `pid`, summed per thread name (/proc/<pid>/task/*/comm).
std::map<std::string, double> threadCpuTicks(pid_t pid);
void writeFile(const std::string& path, const std::string& text);
bool exists(const std::string& path);
/// stdout and stderr of a shell command, bounded by `timeout timeout_s`.
std::string captureOutput(const std::string& cmd, int timeout_s = 60);
/// Polls `pred` every 10 ms until it holds or timeout_s passes.
bool waitUntil(const std::function<bool()>& pred, double timeout_s);
/// Monotonic clock, ns (the same clock mcu_sim writes in its truth log).
int64_t nowNs();
void sleepS(double s);

}  // namespace inspect::test
