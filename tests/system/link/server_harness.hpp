#pragma once
// The real pc_server for the link load and malformed-input tests: mutual TLS
// with the tests' certificates, 127.0.0.1 and an ephemeral port, recording on
// into a temporary runs directory, no video, and the operator console on a
// FIFO so that the caller can type commands (select, record start/stop, quit)
// while it runs. Plus what the measurements need: /proc figures of the
// process and the telemetry a run's MCAP recorded, read back with the
// project's MCAP reader. Every wait is bounded in time.
#include <sys/types.h>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "tests/support/process.hpp"

namespace inspect::linktest {

struct ServerStart {
  std::string dir;                       // working directory for logs, runs, FIFO
  std::string certs_dir;                 // --certs
  std::string config_path;               // --config ("" = config/server.yaml of the source tree)
  std::vector<std::string> extra_args;
};

/// CPU and memory of a process from /proc.
struct ProcSample {
  bool ok = false;
  uint64_t cpu_ticks = 0;    // utime + stime, clock ticks (sysconf(_SC_CLK_TCK))
  uint64_t rss_kb = 0;       // VmRSS
  uint64_t hwm_kb = 0;       // VmHWM (peak RSS over the process's life)
  uint64_t threads = 0;
  uint64_t rchar = 0, wchar = 0;  // /proc/<pid>/io: bytes through read/write calls (sockets and files)
};
ProcSample sampleProc(pid_t pid);
double clockTicksPerSecond();

class ServerUnderTest {
 public:
  ServerUnderTest() = default;
  ~ServerUnderTest();
  ServerUnderTest(const ServerUnderTest&) = delete;
  ServerUnderTest& operator=(const ServerUnderTest&) = delete;

  /// Starts pc_server; false (with error()) if it did not report its port within 10 s.
  bool start(const ServerStart& s);
  const std::string& error() const { return error_; }
  uint16_t port() const { return port_; }
  pid_t pid() const { return proc_.pid(); }
  bool running() { return proc_.running(); }
  const std::string& runsDir() const { return runs_dir_; }

  /// One console line (written to the server's stdin FIFO).
  bool console(const std::string& line);
  /// Everything the console printed / the log so far.
  std::string out() const;
  std::string log() const;
  /// Waits until the console output contains `needle` at least `count` times.
  bool waitOut(const std::string& needle, std::size_t count, double timeout_s) const;

  /// Drain barrier: each robot sends Event INFO `marker`; true once the console printed
  /// all of them, i.e. the server has processed everything they sent before.
  template <class Robots>
  bool drain(const Robots& robots, const std::string& marker, double timeout_s) {
    const std::size_t before = countOut("] INFO: " + marker);
    for (const auto& r : robots) r->sendEvent(marker);
    return waitOut("] INFO: " + marker, before + robots.size(), timeout_s);
  }
  std::size_t countOut(const std::string& needle) const;

  /// `select id` + `record start name`; false when the console did not confirm within timeout_s.
  /// The run id is kept (runId()).
  bool recordStart(const std::vector<std::string>& robots, const std::string& name, double timeout_s);
  /// `select id` + `record stop` for each; false when not confirmed within timeout_s.
  bool recordStop(const std::vector<std::string>& robots, double timeout_s);
  std::string runId(const std::string& robot) const;
  std::string mcapPath(const std::string& robot) const;

  /// `quit` and wait for the exit; SIGTERM/SIGKILL after timeout_s. The exit status, nullopt when killed.
  std::optional<int> quit(double timeout_s);

 private:
  test::Process proc_;
  std::string dir_, runs_dir_, fifo_, error_;
  int fifo_fd_ = -1;
  uint16_t port_ = 0;
  std::map<std::string, std::string> run_ids_;
};

/// One telemetry message as a run's MCAP recorded it.
struct RecordedTelemetry {
  uint64_t seq = 0;          // Telemetry.serial.frames_ok (FleetRobot's telemetry sequence number)
  uint64_t send_us = 0;      // MCAP publish_time (= Envelope.send_time_us, the sender's CLOCK_MONOTONIC)
  uint64_t log_time_ns = 0;  // MCAP log_time: the server's receive time (CLOCK_MONOTONIC) as wall-clock ns
};
/// The /telemetry messages of an MCAP file, in file order. Throws std::runtime_error.
std::vector<RecordedTelemetry> readTelemetry(const std::string& mcap_path);

/// CLOCK_REALTIME - CLOCK_MONOTONIC, ns, from the tightest of `tries` readings.
int64_t wallMinusMonoNs(int tries = 50);

/// Sequence check of one robot's recording against what it sent (1..sent).
struct SeqCheck {
  uint64_t sent = 0, recorded = 0, missing = 0, duplicates = 0, out_of_order = 0, unexpected = 0;
  uint64_t first_missing = 0;
};
SeqCheck checkSequence(const std::vector<RecordedTelemetry>& rec, uint64_t sent);

}  // namespace inspect::linktest
