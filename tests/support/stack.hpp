#pragma once
// The three real programs wired together on loopback for integration tests,
// plus a reader of mcu_sim's ground-truth log.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "tests/support/paths.hpp"
#include "tests/support/process.hpp"

namespace inspect::test {

/// One `T` row of the truth log (100 Hz).
struct TruthRow {
  int64_t mono_ns = 0;
  double t = 0, x = 0, y = 0, theta = 0, wheel_l = 0, wheel_r = 0, set_l = 0, set_r = 0;
  unsigned flags = 0;
};
/// One `C` row: a wheel command the simulated MCU accepted.
struct TruthCommand {
  int64_t mono_ns = 0;
  double t = 0;
  int seq = 0, left = 0, right = 0, flags = 0;
};
/// One `E` row.
struct TruthEvent {
  int64_t mono_ns = 0;
  double t = 0;
  std::string name, detail;
};
/// One `P` row: a present pedestrian (10 Hz of sim time).
struct TruthPerson {
  double t = 0;
  std::string id;
  double x = 0, y = 0, vx = 0, vy = 0, robot_dist = 0;
};
/// One `G` row: gas at the sensor inlet (10 Hz of sim time), per channel the true value and the reading.
struct TruthGas {
  int64_t mono_ns = 0;
  double t = 0, x = 0, y = 0;
  std::vector<double> truth, reading;
};
struct Truth {
  std::vector<TruthRow> rows;
  std::vector<TruthGas> gas;
  std::vector<TruthPerson> people;
  std::vector<TruthCommand> commands;
  std::vector<TruthEvent> events;
};
Truth readTruth(const std::string& path);

/// The value a console `expect` printed for `field` ("expect ok (line N):
/// field = V"), its `occurrence`-th time (0 = the first); NaN when absent.
double expectedValue(const std::string& console_out, const std::string& field, int occurrence = 0);

/// The robot's sensor timeout in the tests that do not measure that failsafe
/// (config/client.yaml's 0.1 s is kept by the fault tests). On a shared test
/// host the kernel itself can hold a pseudo-terminal's bytes for longer: a
/// pty's reads are delivered by a tty work item on a normal-priority kernel
/// worker, and ftrace on this 2-core VM, stack phase beside a nice build,
/// measured that work item's queue-to-run delay at p99.9 48 ms and up to
/// 331 ms (idle: up to 15 ms; docs/testing.md). A stack test whose robot
/// latched FAILSAFE on that would fail on what it does not check.
inline constexpr const char* kSharedHostSensorTimeoutS = "0.5";
/// config/client.yaml with `safety.sensor_timeout_s` set to
/// kSharedHostSensorTimeoutS, written to <dir>/client-shared-host.yaml;
/// returns its path.
std::string sharedHostClientConfig(const TempDir& dir);


/// A simulated robot: mcu_sim + robot_client.
struct RobotProcs {
  std::string id;
  std::string pty;      // symlink to the pty robot_client opens
  std::string truth;    // mcu_sim's truth log
  std::string cmd_log;  // robot_client's sent wheel commands
  std::vector<std::string> client_argv;  // how robot_client was started (restartClient)
  Process sim;
  Process client;
};

class Stack {
 public:
  explicit Stack(const std::string& tag) : dir_(tag) {}
  ~Stack();

  const TempDir& dir() const { return dir_; }

  /// Video on for the programs started after this call (off by default: it
  /// costs CPU that the timing of other tests should not share). The server
  /// gets an ephemeral UDP port and <dir>/video; robots send to that port.
  void enableVideo() { video_ = true; }
  int videoPort() const { return video_port_; }
  std::string videoDir() const { return dir_ / "video"; }

  /// The Foxglove bridge on for the server started after this call (off by
  /// default: port 8765 is not the tests'): an ephemeral port, a token in <dir>/foxglove.token.
  void enableFoxglove() { foxglove_ = true; }
  int foxglovePort() const { return foxglove_port_; }
  std::string foxgloveToken() const;

  /// The robots started after this call are as deployed, for the tests that
  /// measure the failsafes (fault_inject): config/client.yaml's sensor
  /// timeout, and an mcu_sim that catches up after a stall of its own. By
  /// default a stack test's robot gets sharedHostClientConfig() and an
  /// mcu_sim whose world waits through its stalls (--freeze-on-stall): a test
  /// of tracking, navigation, video or recording then measures the software,
  /// not how long the shared host left the simulated MCU unrun.
  void measureFailsafes() { measure_failsafes_ = true; }
  /// The robots started after this call get an mcu_sim that simulates a
  /// stall of its own in one step (no --freeze-on-stall), for a test that
  /// times a manoeuvre by the wall clock (drive for 2 s, then stop): a world
  /// that waited would move less than the operator's wait said.
  void catchUpAfterStalls() { catch_up_ = true; }
  /// The robots started after this call run the real firmware: the QEMU
  /// board's image `elf` under scripts/mcu_qemu.sh, with mcu_sim --hil
  /// keeping the world and its truth log (docs/firmware.md). robot_client
  /// opens the board's USART1 exactly as it opens mcu_sim's pty.
  void useFirmware(std::string elf) { firmware_elf_ = std::move(elf); }
  /// robot_client is started through this command for the robots started
  /// after this call (bench_loop: {"taskset", "-c", "1"}).
  void setClientPrefix(std::vector<std::string> prefix) { client_prefix_ = std::move(prefix); }

  /// Starts pc_server on an ephemeral port running `script` (console commands).
  /// Returns false if it did not report its port within 10 s.
  bool startServer(const std::string& script, const std::vector<std::string>& extra = {});
  /// Starts mcu_sim (world file under config/worlds, or an absolute path) and a robot_client.
  /// `relay_args` non-empty puts tests' serial_relay between them.
  RobotProcs& startRobot(const std::string& id, const std::string& world = "square_room.yaml",
                         const std::vector<std::string>& relay_args = {},
                         const std::vector<std::string>& sim_args = {},
                         const std::vector<std::string>& client_args = {});
  /// Starts robot `id`'s robot_client again as it was started (after the
  /// test killed it), its output appended to the same files.
  void restartClient(const std::string& id);
  Process& server() { return server_; }
  int port() const { return port_; }
  std::string serverOutput() const { return readFile(dir_ / "server.out"); }
  /// Everything the processes printed, for failure messages.
  std::string logs() const;

  Process& relay(const std::string& id) { return relays_.at(id); }

 private:
  TempDir dir_;
  Process server_;
  int port_ = 0;
  bool video_ = false;
  int video_port_ = 0;
  bool foxglove_ = false;
  int foxglove_port_ = 0;
  bool measure_failsafes_ = false;
  bool catch_up_ = false;
  std::vector<std::string> client_prefix_;
  std::string firmware_elf_;
  std::vector<std::unique_ptr<RobotProcs>> robots_;
  std::map<std::string, Process> relays_;
};

/// A topic's message count in the JSON that tests/tools/mcap_reader prints
/// ({"/robot1/telemetry": n, ...}); -1 when the topic is not there.
int mcapTopicCount(const std::string& reader_json, const std::string& topic);

}  // namespace inspect::test
