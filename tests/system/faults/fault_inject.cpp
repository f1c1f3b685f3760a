// fault_inject: the failsafes measured through the real programs (issue 9).
//
// Runs pc_server (a console script), mcu_sim and robot_client (tests'
// Stack), drives the robot (teleop: spinning on the spot, so the wheels turn
// for as long as needed), and repeats each fault N times: server SIGKILL /
// SIGSTOP, client SIGKILL / SIGSTOP, serial line cut, telemetry stale (the
// robot -> server direction of the TCP link stops), sensor frames stale (the
// MCU -> Pi direction of the serial line stops). The time from the fault to
// the wheels at zero comes from mcu_sim's ground truth; detection times from
// the programs' log lines. After each fault it checks that nothing restarts by
// itself, recovers (restart / SIGCONT / release the line), and checks that
// telemetry and video come back without restarting the other processes.
//
// --ber runs the serial bit-error test instead: bit errors injected by
// serial_relay, frames lost per direction, and no wheel command or sensor
// frame accepted that was not sent unmodified.
//
// docs/failsafes.md describes the faults, the figures and how to run this.
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "shared/util/cli_args.hpp"
#include "shared/serial/frame_codec.hpp"
#include "tests/support/stack.hpp"

using namespace inspect::test;

namespace {

// ---------------------------------------------------------------- settings

constexpr double kDriveW = 1.5;                            // rad/s, spinning on the spot
constexpr double kWheelTarget = kDriveW * 0.438 / 2 / 0.2;  // 1.64 rad/s per wheel (config/robot.yaml)
constexpr double kAtSpeed = 0.8 * kWheelTarget;
constexpr double kStill = 0.05;  // rad/s: "wheels stopped" (1 cm/s at the tyre)

struct Options {
  int trials = 30;
  std::vector<std::string> faults;  // empty: all
  std::set<std::string> allow_miss;
  // For the exit status only: a p99 over its target by at most this much does
  // not fail the run (the tables still say NO). The ctest short version runs on
  // shared CI machines, where scheduling can delay any process by tens of ms;
  // the targets themselves are judged by the long run (docs/failsafes.md).
  double margin_ms = 0;
  std::string json;
  bool video = true;
  double hold_s = 1.3;  // how long a fault lasts before recovery
  unsigned seed = 1;
  bool ber = false;
  std::vector<double> ber_rates = {1e-4, 1e-3};
  double ber_seconds = 45;
  double garbage_per_s = 0;  // serial_relay --garbage-per-s in the BER test
  bool verbose = false;
  // Faults run at once, each on its own stack (the short form in ctest: 2;
  // the measurement: 1, the machine to itself).
  int jobs = 1;
  // The MCU: empty, mcu_sim's emulator; else the firmware's QEMU image (mcu_sim --hil).
  std::string firmware;
};

// ---------------------------------------------------------------- small helpers

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

void note(const Options& o, const std::string& s) {
  if (o.verbose) std::fprintf(stderr, "fault_inject: %s\n", s.c_str());
}

double ms(int64_t ns) { return static_cast<double>(ns) / 1e6; }

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(s);
  while (std::getline(in, cell, sep))
    if (!cell.empty()) out.push_back(cell);
  return out;
}

std::string fileTail(const std::string& path, std::size_t from) {
  const std::string all = readFile(path);
  return from < all.size() ? all.substr(from) : std::string();
}

std::size_t fileSize(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 ? static_cast<std::size_t>(st.st_size) : 0;
}

/// argv of a running process (to start it again exactly as the Stack did).
std::vector<std::string> cmdline(pid_t pid) {
  const std::string raw = readFile("/proc/" + std::to_string(pid) + "/cmdline");
  std::vector<std::string> out;
  std::string cur;
  for (char c : raw) {
    if (c == '\0') {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  return out;
}

/// Writes one command into a relay's control FIFO.
bool control(const std::string& fifo, const std::string& cmd) {
  const int fd = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);
  if (fd < 0) return false;
  const std::string line = cmd + "\n";
  const bool ok = ::write(fd, line.data(), line.size()) == static_cast<ssize_t>(line.size());
  ::close(fd);
  return ok;
}

/// Waits for "<prefix><cmd> at mono_ns=N" in a relay's output after byte `from`; N or nullopt.
std::optional<int64_t> relayAck(const std::string& out_path, std::size_t from, const std::string& what) {
  std::optional<int64_t> at;
  waitUntil(
      [&] {
        const std::string t = fileTail(out_path, from);
        const auto p = t.find(what + " at mono_ns=");
        if (p == std::string::npos) return false;
        at = std::stoll(t.substr(p + what.size() + 12));
        return true;
      },
      3.0);
  return at;
}

// Log lines ("HH:MM:SS.mmm L [tag] text", local wall clock) -> monotonic ns.
struct LogLine {
  int64_t mono_ns;
  std::string text;
};

int64_t localMsOfDay(std::chrono::system_clock::time_point tp) {
  const auto t = std::chrono::system_clock::to_time_t(tp);
  std::tm tm{};
  localtime_r(&t, &tm);
  const auto msec = std::chrono::duration_cast<std::chrono::milliseconds>(tp.time_since_epoch()).count() % 1000;
  return ((tm.tm_hour * 60 + tm.tm_min) * 60 + tm.tm_sec) * 1000LL + msec;
}

std::vector<LogLine> readLog(const std::string& path) {
  const int64_t mono_now = nowNs();
  const int64_t wall_now_ms = localMsOfDay(std::chrono::system_clock::now());
  std::vector<LogLine> out;
  std::istringstream in(readFile(path));
  std::string line;
  while (std::getline(in, line)) {
    int h, m, s, msec;
    if (line.size() < 14 || std::sscanf(line.c_str(), "%2d:%2d:%2d.%3d", &h, &m, &s, &msec) != 4 || line[2] != ':')
      continue;
    int64_t diff = ((h * 60LL + m) * 60 + s) * 1000 + msec - wall_now_ms;
    if (diff > 12 * 3600 * 1000LL) diff -= 24 * 3600 * 1000LL;
    if (diff < -12 * 3600 * 1000LL) diff += 24 * 3600 * 1000LL;
    // The line shows the ms truncated: its middle is half a ms later.
    out.push_back({mono_now + diff * 1'000'000 + 500'000, line.substr(13)});
  }
  return out;
}

std::optional<int64_t> firstLogAfter(const std::vector<LogLine>& log, int64_t after_ns, const std::string& pattern) {
  for (const auto& l : log)
    if (l.mono_ns >= after_ns - 1'000'000 && l.text.find(pattern) != std::string::npos) return l.mono_ns;
  return std::nullopt;
}

// ---------------------------------------------------------------- ground truth, read as it grows

class TruthTail {
 public:
  explicit TruthTail(std::string path) : path_(std::move(path)) {}
  void poll() {
    const int fd = ::open(path_.c_str(), O_RDONLY);
    if (fd < 0) return;
    char buf[65536];
    for (;;) {
      const ssize_t n = ::pread(fd, buf, sizeof buf, offset_);
      if (n <= 0) break;
      offset_ += n;
      partial_.append(buf, static_cast<std::size_t>(n));
    }
    ::close(fd);
    std::size_t start = 0;
    for (auto nl = partial_.find('\n'); nl != std::string::npos; nl = partial_.find('\n', start)) {
      parse(partial_.substr(start, nl - start));
      start = nl + 1;
    }
    partial_.erase(0, start);
  }
  std::vector<TruthRow> rows;
  std::vector<TruthCommand> commands;
  std::vector<TruthEvent> events;

 private:
  void parse(const std::string& l) {
    if (l.size() < 3 || l[1] != ',') return;
    if (l[0] == 'T') {
      TruthRow r;
      long long mono;
      if (std::sscanf(l.c_str(), "T,%lld,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%u", &mono, &r.t, &r.x, &r.y, &r.theta,
                      &r.wheel_l, &r.wheel_r, &r.set_l, &r.set_r, &r.flags) == 10) {
        r.mono_ns = mono;
        rows.push_back(r);
      }
    } else if (l[0] == 'C') {
      TruthCommand c;
      long long mono;
      if (std::sscanf(l.c_str(), "C,%lld,%lf,%d,%d,%d,%d", &mono, &c.t, &c.seq, &c.left, &c.right, &c.flags) == 6) {
        c.mono_ns = mono;
        commands.push_back(c);
      }
    } else if (l[0] == 'E') {
      const auto f = split(l, ',');
      if (f.size() < 4) return;
      TruthEvent e;
      e.mono_ns = std::stoll(f[1]);
      e.t = std::stod(f[2]);
      e.name = f[3];
      e.detail = f.size() > 4 ? f[4] : "";
      events.push_back(e);
    }
  }
  std::string path_;
  off_t offset_ = 0;
  std::string partial_;
};

// ---------------------------------------------------------------- statistics

struct Stats {
  std::vector<double> v;
  void add(double x) { v.push_back(x); }
  std::size_t n() const { return v.size(); }
  double pct(double q) const {
    if (v.empty()) return NAN;
    auto s = v;
    std::sort(s.begin(), s.end());
    const auto i = static_cast<std::size_t>(std::max(1.0, std::ceil(q * static_cast<double>(s.size())))) - 1;
    return s[std::min(i, s.size() - 1)];
  }
  double max() const { return v.empty() ? NAN : *std::max_element(v.begin(), v.end()); }
  std::string cell() const {
    if (v.empty()) return "-";
    return fmt("%.0f", pct(0.5)) + " / " + fmt("%.0f", pct(0.99)) + " / " + fmt("%.0f", max());
  }
  std::string json() const {
    std::string s = "{\"n\": " + std::to_string(v.size());
    if (!v.empty())
      s += ", \"p50\": " + fmt("%.2f", pct(0.5)) + ", \"p99\": " + fmt("%.2f", pct(0.99)) + ", \"max\": " +
           fmt("%.2f", max());
    s += ", \"values\": [";
    for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + fmt("%.2f", v[i]);
    return s + "]}";
  }
};

// ---------------------------------------------------------------- faults

enum class Fault { kServerKill, kServerStop, kClientKill, kClientStop, kSerialCut, kTelemetryStale, kSensorStale };

// The MCU watchdog stops the motors 200 ms after the last valid wheel
// command, on a 1 ms tick; measured from the fault the last command may still
// have been on the wire: a 200 ms target is met within this.
constexpr double kWatchdogSlackMs = 2.0;

struct Detector {
  const char* name;     // table label
  const char* source;   // "client", "server", "truth"
  const char* pattern;  // log text or truth event
  double target_ms;     // 0: none
  double slack_ms = 0;  // met when p99 <= target + slack (kWatchdogSlackMs for the MCU watchdog)
};

struct FaultDef {
  Fault f;
  const char* name;
  const char* label;
  double target_ms;  // on the headline figure (set-points zero)
  const char* target_what;
  std::vector<Detector> detectors;
  double slack_ms = 0;  // see Detector::slack_ms
};

const std::vector<FaultDef>& faultDefs() {
  static const std::vector<FaultDef> k = {
      {Fault::kServerKill, "server_sigkill", "server SIGKILL", 300, "link loss -> stop",
       {{"robot: link closed", "client", "W [link]", 0}, {"robot: FAILSAFE", "client", "MODE_CHANGE: FAILSAFE", 0}}},
      {Fault::kServerStop, "server_sigstop", "server SIGSTOP (half-open TCP)", 300, "link loss -> stop",
       {{"robot: LINK_LOST raised", "client", "FAULT_RAISED: link lost", 0},
        {"robot: FAILSAFE", "client", "MODE_CHANGE: FAILSAFE", 0},
        {"robot: half-open link closed", "client", "W [link]", 1000}}},
      {Fault::kClientKill, "client_sigkill", "client SIGKILL", 200, "client death -> MCU stop",
       {{"MCU watchdog trip", "truth", "watchdog_trip", 200, kWatchdogSlackMs}},
       kWatchdogSlackMs},
      {Fault::kClientStop, "client_sigstop", "client SIGSTOP", 200, "client death -> MCU stop",
       {{"MCU watchdog trip", "truth", "watchdog_trip", 200, kWatchdogSlackMs},
        {"server: session closed", "server", "session timeout", 0}},
       kWatchdogSlackMs},
      {Fault::kSerialCut, "serial_cut", "serial line cut (both directions)", 300, "link loss -> stop",
       {{"robot: SENSOR_STALE raised", "client", "FAULT_RAISED: sensor frames stale", 0},
        {"robot: FAILSAFE", "client", "MODE_CHANGE: FAILSAFE", 0},
        {"MCU watchdog trip", "truth", "watchdog_trip", 200, kWatchdogSlackMs}}},
      {Fault::kTelemetryStale, "telemetry_stale", "telemetry stale (robot->server TCP stops)", 300,
       "link loss -> stop",
       {{"server: telemetry stale, EStop sent", "server", "while moving: EStop sent", 0},
        {"robot: stopped by that EStop", "client", "MODE_CHANGE: ESTOP", 0},
        {"server: session closed", "server", "session timeout", 0},
        {"robot: link closed", "client", "W [link]", 0},
        {"robot: FAILSAFE", "client", "MODE_CHANGE: FAILSAFE", 0}}},
      {Fault::kSensorStale, "sensor_stale", "sensor frames stale (MCU->Pi stops)", 300, "link loss -> stop",
       {{"robot: SENSOR_STALE raised", "client", "FAULT_RAISED: sensor frames stale", 0},
        {"robot: FAILSAFE", "client", "MODE_CHANGE: FAILSAFE", 0}}},
  };
  return k;
}

// One console script (one pc_server process), line numbers remembered.
struct Script {
  std::vector<std::string> lines;
  int add(const std::string& l) {
    lines.push_back(l);
    return static_cast<int>(lines.size());
  }
  std::string text() const {
    std::string s;
    for (const auto& l : lines) s += l + "\n";
    return s;
  }
};

// Checks made by the console after a trial's recovery (line numbers in one script).
struct RecoveryLines {
  int connected = 0, telemetry = 0, sensors = 0, mode = 0, video = 0;
};

int markerDeg(int k) { return 1 + k % 170; }

void prologue(Script& s) {
  s.add("expect robots >= 1 within 30");
  s.add("expect connected == 1 within 30");
  s.add("expect sensor_hz > 50 within 15");
}

RecoveryLines recoveryChecks(Script& s, bool video) {
  RecoveryLines r;
  r.connected = s.add("expect connected == 1 within 20");
  r.telemetry = s.add("expect telemetry_age < 0.5 within 10");
  r.sensors = s.add("expect sensor_hz > 50 within 10");
  r.mode = s.add("expect mode == FAILSAFE");
  if (video) {
    s.add("wait 1.2");
    r.video = s.add("video stats");
  }
  return r;
}

void trialStart(Script& s, int k, double wait_s) {
  s.add("echo --- trial " + std::to_string(k) + " ---");
  s.add("ptz " + std::to_string(markerDeg(k)) + " 0");  // the marker: an E ptz row in the truth log
  s.add("try resume");
  s.add("drive 0 " + fmt("%.2f", kDriveW));
  s.add("wait " + fmt("%.2f", wait_s));
}

struct TrialResult {
  int k = 0;
  bool injected = false;
  std::string error;
  std::optional<double> set_zero_ms, set_zero_trow_ms, still_ms;
  std::map<std::string, double> detect_ms;
  std::optional<double> reconnect_ms;  // recovery -> robot_client "connected" again
  bool no_restart = false;
  double zero_held_after_recovery_s = 0;
  std::string restart_detail;
  bool telemetry_ok = false;
  bool video_ok = false;
  double video_fps = 0;
  std::string mode_after;
};

struct FaultResult {
  const FaultDef* def = nullptr;
  std::vector<TrialResult> trials;
  std::string setup_error;
  std::string dir;
};

// Result of one "expect" line in a server's output: ok, and the value text.
std::pair<bool, std::string> expectResult(const std::string& out, int line) {
  const std::string ok = "expect ok (line " + std::to_string(line) + "): ";
  const std::string bad = "EXPECT FAILED (line " + std::to_string(line) + "): ";
  for (const auto& [tag, good] : {std::pair{ok, true}, std::pair{bad, false}}) {
    const auto p = out.find(tag);
    if (p == std::string::npos) continue;
    const auto e = out.find('\n', p);
    return {good, out.substr(p + tag.size(), e == std::string::npos ? std::string::npos : e - p - tag.size())};
  }
  return {false, "(no result)"};
}

double videoDecodedFps(const std::string& out, int line) {
  const auto p = out.find("[" + std::to_string(line) + "] video stats");
  if (p == std::string::npos) return -1;
  const auto q = out.find("decoded ", out.find("received", p));
  if (q == std::string::npos || out.find("[" + std::to_string(line + 1) + "]", p) < q) return 0;
  return std::atof(out.c_str() + q + 8);
}

class FaultRunner {
 public:
  FaultRunner(const FaultDef& def, const Options& o, std::mt19937& rng) : def_(def), o_(o), rng_(rng) {}

  FaultResult run() {
    FaultResult res;
    res.def = &def_;
    Stack s(std::string("fault-") + def_.name);
    s.measureFailsafes();
    if (!o_.firmware.empty()) s.useFirmware(o_.firmware);
    res.dir = s.dir().path();
    if (o_.video) s.enableVideo();
    const bool kill_server = def_.f == Fault::kServerKill;
    // Trial timeline: at speed ~1.2 s after the marker, up to 0.25 s random
    // delay, the fault for hold_s, then at least ~1.5 s of "no restart" check
    // before the console's recovery checks and the next trial.
    const double wait_s = kill_server ? 60 : 1.6 + 0.25 + o_.hold_s + 1.6;
    const int n = o_.trials;

    std::vector<Script> scripts;
    std::vector<RecoveryLines> rec(static_cast<std::size_t>(n));
    std::vector<int> rec_script(static_cast<std::size_t>(n));  // which script holds trial k's checks
    if (kill_server) {
      for (int i = 0; i <= n; ++i) {
        Script sc;
        prologue(sc);
        if (i > 0) rec[static_cast<std::size_t>(i - 1)] = recoveryChecks(sc, o_.video), rec_script[i - 1] = i;
        if (i < n) trialStart(sc, i, wait_s);
        else sc.add("stop"), sc.add("wait 0.5");
        scripts.push_back(sc);
      }
    } else {
      Script sc;
      prologue(sc);
      for (int k = 0; k < n; ++k) {
        if (k > 0) rec[static_cast<std::size_t>(k - 1)] = recoveryChecks(sc, o_.video);
        trialStart(sc, k, wait_s);
      }
      rec[static_cast<std::size_t>(n - 1)] = recoveryChecks(sc, o_.video);
      sc.add("stop");
      sc.add("wait 0.5");
      scripts.push_back(sc);
    }

    if (!s.startServer(scripts[0].text())) {
      res.setup_error = "pc_server did not start\n" + s.logs();
      return res;
    }
    const int port = s.port();
    std::vector<std::string> relay_args, client_args;
    const std::string serial_ctl = s.dir() / "serial.ctl", tcp_ctl = s.dir() / "tcp.ctl";
    Process tcp_relay;
    if (def_.f == Fault::kSerialCut || def_.f == Fault::kSensorStale) relay_args = {"--control", serial_ctl};
    if (def_.f == Fault::kTelemetryStale) {
      tcp_relay = Process::spawn({binPath("tcp_fault_relay"), "--target", "127.0.0.1:" + std::to_string(port),
                                  "--port-file", s.dir() / "tcp_port", "--control", tcp_ctl},
                                 s.dir() / "tcprelay.out", s.dir() / "tcprelay.err");
      if (!waitUntil([&] { return exists(s.dir() / "tcp_port"); }, 10)) {
        res.setup_error = "tcp_fault_relay did not start: " + readFile(s.dir() / "tcprelay.err");
        return res;
      }
      client_args = {"--server", "127.0.0.1:" + std::string(readFile(s.dir() / "tcp_port").c_str())};
      client_args.back().erase(client_args.back().find_last_not_of("\n") + 1);
    }
    auto& robot = s.startRobot("robot1", "square_room.yaml", relay_args, {}, client_args);
    const std::string client_err = s.dir() / "robot1-client.err", server_err = s.dir() / "server.err",
                      server_out = s.dir() / "server.out";
    TruthTail truth(robot.truth);
    // robot_client's argv as the Stack started it (TLS files included), once it has exec'd.
    std::vector<std::string> client_argv;
    auto isClient = [](const std::vector<std::string>& argv) {
      return !argv.empty() && argv[0].size() >= 12 && argv[0].compare(argv[0].size() - 12, 12, "robot_client") == 0;
    };
    if (!waitUntil([&] { return isClient(client_argv = cmdline(robot.client.pid())); }, 10)) {
      res.setup_error = "robot_client did not start\n" + s.logs();
      return res;
    }
    std::vector<std::size_t> out_offset(scripts.size(), 0);

    std::optional<int64_t> marker = waitMarker(truth, 0, 0, 90);
    if (!marker) {
      res.setup_error = "trial 0 did not start (no marker)\n" + s.logs();
      return res;
    }
    for (int k = 0; k < n; ++k) {
      TrialResult tr;
      tr.k = k;
      const int64_t m_k = *marker;
      // 1. At speed.
      const bool at_speed = waitUntil(
          [&] {
            truth.poll();
            int good = 0;
            for (auto it = truth.rows.rbegin(); it != truth.rows.rend() && it->mono_ns > m_k; ++it) {
              if (std::abs(it->wheel_l) < kAtSpeed || std::abs(it->wheel_r) < kAtSpeed) break;
              if (++good >= 20) return true;
            }
            return false;
          },
          10);
      int64_t t_f = 0, t_r = 0;
      if (!at_speed) {
        tr.error = "the robot did not reach speed after the trial's drive";
      } else {
        sleepS(std::uniform_real_distribution<double>(0, 0.25)(rng_));
        // 2. The fault.
        t_f = inject(s, robot, serial_ctl, tcp_ctl, &tr);
        tr.injected = t_f > 0;
        if (!tr.injected && tr.error.empty()) tr.error = "could not inject the fault";
        const int64_t until = (t_f > 0 ? t_f : nowNs()) + static_cast<int64_t>(o_.hold_s * 1e9);
        while (nowNs() < until) sleepS(0.02);
      }
      // 3. Recovery (always, so that the next trial has a stack).
      if (kill_server) {
        if (tr.injected) {
          t_r = nowNs();
          out_offset[static_cast<std::size_t>(k + 1)] = fileSize(server_out);
          std::error_code ec;
          std::filesystem::remove(s.dir() / "port", ec);
          std::filesystem::remove(s.dir() / "video_port", ec);
          std::vector<std::string> extra = {"--port", std::to_string(port)};
          if (o_.video) extra.insert(extra.end(), {"--video-port", std::to_string(s.videoPort())});
          if (!s.startServer(scripts[static_cast<std::size_t>(k + 1)].text(), extra)) {
            tr.error = "pc_server did not restart on port " + std::to_string(port);
            res.trials.push_back(tr);
            break;
          }
        } else {
          // The first server is still running its trial: nothing to recover, and nothing more to do.
          res.trials.push_back(tr);
          break;
        }
      } else if (tr.injected) {
        t_r = recover(s, robot, serial_ctl, tcp_ctl, client_argv, &tr);
      }
      // 4. Until the console's next trial (or its end).
      std::optional<int64_t> next;
      if (k + 1 < n) {
        next = waitMarker(truth, k + 1, m_k, 60);
        if (!next) tr.error += (tr.error.empty() ? "" : "; ") + std::string("the next trial did not start");
      } else {
        s.server().wait(60);
      }
      truth.poll();
      const int64_t end = next ? *next : nowNs();
      if (tr.injected) analyse(tr, truth, t_f, t_r, end, client_err, server_err);
      // 5. The console's checks after recovery.
      const std::size_t si = kill_server ? static_cast<std::size_t>(rec_script[static_cast<std::size_t>(k)]) : 0;
      const std::string out = fileTail(server_out, out_offset[si]);
      const auto& rl = rec[static_cast<std::size_t>(k)];
      const auto c = expectResult(out, rl.connected), t = expectResult(out, rl.telemetry),
                 sh = expectResult(out, rl.sensors), md = expectResult(out, rl.mode);
      tr.telemetry_ok = c.first && t.first && sh.first;
      if (!tr.telemetry_ok)
        tr.error += (tr.error.empty() ? "" : "; ") + std::string("telemetry not restored: connected ") + c.second +
                    ", telemetry_age " + t.second + ", sensor_hz " + sh.second;
      tr.mode_after = md.second.substr(0, md.second.find(','));
      if (tr.mode_after.rfind("mode = ", 0) == 0) tr.mode_after = tr.mode_after.substr(7);
      if (o_.video) {
        tr.video_fps = videoDecodedFps(out, rl.video);
        tr.video_ok = tr.video_fps >= 10;
        if (!tr.video_ok) tr.error += (tr.error.empty() ? "" : "; ") + fmt("video not restored (%.1f fps decoded)", tr.video_fps);
      }
      note(o_, std::string(def_.name) + " trial " + std::to_string(k) + ": set-points zero " +
                   (tr.set_zero_ms ? fmt("%.1f ms", *tr.set_zero_ms) : "-") + ", still " +
                   (tr.still_ms ? fmt("%.0f ms", *tr.still_ms) : "-") + (tr.error.empty() ? "" : " ERROR " + tr.error));
      std::fprintf(stderr, "%s", tr.error.empty() ? "." : "x");
      res.trials.push_back(tr);
      if (!next) break;
      marker = next;
    }
    std::fprintf(stderr, "\n");
    if (!res.setup_error.empty() || std::any_of(res.trials.begin(), res.trials.end(),
                                                [](const TrialResult& t) { return !t.error.empty(); }))
      res.setup_error += o_.verbose ? s.logs() : "";
    s.server().signal(SIGCONT);
    robot.client.signal(SIGCONT);
    tcp_relay.terminate();
    return res;
  }

 private:
  // The marker of trial k: a `ptz k 0` the MCU logged after `after_ns`.
  std::optional<int64_t> waitMarker(TruthTail& truth, int k, int64_t after_ns, double timeout_s) {
    const long want = std::lround(markerDeg(k) * M_PI / 180.0 * 1e4);
    std::optional<int64_t> at;
    waitUntil(
        [&] {
          truth.poll();
          for (const auto& e : truth.events) {
            if (e.name != "ptz" || e.mono_ns <= after_ns) continue;
            const auto p = e.detail.find("pan_0p1mrad=");
            if (p != std::string::npos && std::labs(std::atol(e.detail.c_str() + p + 12) - want) <= 1) {
              at = e.mono_ns;
              return true;
            }
          }
          return false;
        },
        timeout_s);
    return at;
  }

  int64_t inject(Stack& s, RobotProcs& r, const std::string& serial_ctl, const std::string& tcp_ctl,
                 TrialResult* tr) {
    auto viaRelay = [&](const std::string& out, const std::string& fifo, const std::string& cmd) -> int64_t {
      const std::size_t from = fileSize(out);
      if (!control(fifo, cmd)) return 0;
      const auto at = relayAck(out, from, cmd);
      if (!at) tr->error = "relay did not apply '" + cmd + "'";
      return at.value_or(0);
    };
    int64_t t = nowNs();
    switch (def_.f) {
      case Fault::kServerKill: s.server().signal(SIGKILL); break;
      case Fault::kServerStop: s.server().signal(SIGSTOP); break;
      case Fault::kClientKill: r.client.signal(SIGKILL); break;
      case Fault::kClientStop: r.client.signal(SIGSTOP); break;
      case Fault::kSerialCut: t = viaRelay(s.dir() / "robot1-relay.out", serial_ctl, "stall both"); break;
      case Fault::kSensorStale: t = viaRelay(s.dir() / "robot1-relay.out", serial_ctl, "stall down"); break;
      case Fault::kTelemetryStale: t = viaRelay(s.dir() / "tcprelay.out", tcp_ctl, "stall up"); break;
    }
    return t;
  }

  int64_t recover(Stack& s, RobotProcs& r, const std::string& serial_ctl, const std::string& tcp_ctl,
                  const std::vector<std::string>& client_argv, TrialResult* tr) {
    const int64_t t = nowNs();
    switch (def_.f) {
      case Fault::kServerKill: break;  // restarted by the caller
      case Fault::kServerStop: s.server().signal(SIGCONT); break;
      case Fault::kClientKill:
        r.client.wait(5);
        r.client = Process::spawn(client_argv, s.dir() / "robot1-client.out", s.dir() / "robot1-client.err");
        break;
      case Fault::kClientStop: r.client.signal(SIGCONT); break;
      case Fault::kSerialCut:
      case Fault::kSensorStale:
        if (!control(serial_ctl, "flow")) tr->error = "serial_relay: cannot send flow";
        break;
      case Fault::kTelemetryStale:
        if (!control(tcp_ctl, "flow")) tr->error = "tcp_fault_relay: cannot send flow";
        break;
    }
    return t;
  }

  void analyse(TrialResult& tr, const TruthTail& truth, int64_t t_f, int64_t t_r, int64_t end,
               const std::string& client_err, const std::string& server_err) {
    const TruthRow* zero_row = nullptr;
    const TruthRow* prev = nullptr;
    for (const auto& row : truth.rows) {
      if (row.mono_ns < t_f) {
        prev = &row;
        continue;
      }
      if (!zero_row && row.set_l == 0 && row.set_r == 0) zero_row = &row;
      if (!tr.still_ms && std::abs(row.wheel_l) < kStill && std::abs(row.wheel_r) < kStill)
        tr.still_ms = ms(row.mono_ns - t_f);
      if (zero_row && tr.still_ms) break;
      if (!zero_row) prev = &row;
    }
    if (!zero_row) {
      tr.error += (tr.error.empty() ? "" : "; ") + std::string("the set-points never went to zero");
      return;
    }
    tr.set_zero_trow_ms = ms(zero_row->mono_ns - t_f);
    // The exact moment: the zero command or the watchdog trip that the T row shows.
    const int64_t lo = std::max(t_f, prev ? prev->mono_ns : t_f);
    std::optional<int64_t> exact;
    for (const auto& c : truth.commands)
      if (c.mono_ns >= lo && c.mono_ns <= zero_row->mono_ns &&
          ((c.left == 0 && c.right == 0) || !(c.flags & 1))) {
        exact = c.mono_ns;
        break;
      }
    for (const auto& e : truth.events)
      if (e.name == "watchdog_trip" && e.mono_ns >= lo && e.mono_ns <= zero_row->mono_ns && (!exact || e.mono_ns < *exact))
        exact = e.mono_ns;
    tr.set_zero_ms = ms(exact.value_or(zero_row->mono_ns) - t_f);

    // No automatic restart: set-points stay zero until the console's resume + drive of the next trial.
    tr.no_restart = true;
    for (const auto& row : truth.rows) {
      if (row.mono_ns <= zero_row->mono_ns || row.mono_ns >= end) continue;
      if (row.set_l != 0 || row.set_r != 0) {
        tr.no_restart = false;
        tr.restart_detail = fmt("wheels commanded again %.2f s after the fault", ms(row.mono_ns - t_f) / 1000);
        break;
      }
    }
    tr.zero_held_after_recovery_s = ms(end - t_r) / 1000;
    if (!tr.no_restart) tr.error += (tr.error.empty() ? "" : "; ") + tr.restart_detail;
    else if (tr.zero_held_after_recovery_s < 1.0)
      tr.error += (tr.error.empty() ? "" : "; ") + fmt("only %.2f s observed after recovery", tr.zero_held_after_recovery_s);

    // Detection times: what the fault caused while it lasted (a link that was
    // not closed before the recovery was not detected as down).
    const int64_t det_end = std::min(end, t_r + 200'000'000);
    const auto clog = readLog(client_err), slog = readLog(server_err);
    for (const auto& d : def_.detectors) {
      std::optional<int64_t> at;
      const std::string src = d.source;
      if (src == "truth") {
        for (const auto& e : truth.events)
          if (e.name == d.pattern && e.mono_ns >= t_f) {
            at = e.mono_ns;
            break;
          }
      } else {
        at = firstLogAfter(src == "client" ? clog : slog, t_f, d.pattern);
      }
      if (at && *at < det_end) tr.detect_ms[d.name] = ms(*at - t_f);
    }
    if (const auto up = firstLogAfter(clog, t_r, "I [link] connected to"); up && *up < end)
      tr.reconnect_ms = ms(*up - t_r);
  }

  const FaultDef& def_;
  const Options& o_;
  std::mt19937& rng_;
};

// ---------------------------------------------------------------- report

struct Verdict {
  bool ok = true;
  std::vector<std::string> notes;
};

// A p99 against its limit (target + slack): met; over it but allowed
// (--allow-miss); over it by at most --margin-ms; or missed, which fails the run.
enum class Judged { kMet, kAllowed, kInMargin, kMissed };
Judged judge(double p99, double limit, bool allowed, const Options& o) {
  if (p99 <= limit) return Judged::kMet;
  if (allowed) return Judged::kAllowed;
  return p99 <= limit + o.margin_ms ? Judged::kInMargin : Judged::kMissed;
}
std::string missLabel(Judged j, const Options& o) {
  if (j == Judged::kAllowed) return " (allowed)";
  if (j == Judged::kInMargin) return " (within the " + fmt("%.0f", o.margin_ms) + " ms margin)";
  return "";
}

Verdict printFaults(const std::vector<FaultResult>& results, const Options& o, std::string& json) {
  Verdict v;
  std::printf("\nFailsafes, measured: fault -> wheels at zero (ground truth of mcu_sim), %d trial(s) per fault\n", o.trials);
  std::printf("headline = set-points zero: the instant the MCU's applied wheel set-points became 0 (the zero command\n"
              "or the watchdog trip, from the truth log's C/E rows); T row = the first 100 Hz T row showing it;\n"
              "still = both wheels below %.2f rad/s (the motors' %.1f s time constant follows). p50 / p99 / max, ms.\n"
              "MCU watchdog targets are met within +%.0f ms: its 1 ms tick, and a last command still on the wire.\n",
              kStill, 0.2, kWatchdogSlackMs);
  if (o.margin_ms > 0)
    std::printf("--margin-ms %.0f: a p99 over its target by at most that much is NO but does not fail the run.\n",
                o.margin_ms);
  std::printf("\n");
  std::printf("| fault | n | set-points zero | T row | still (< %.2f rad/s) | target | met |\n", kStill);
  std::printf("|---|---|---|---|---|---|---|\n");
  json = "{\n  \"trials_per_fault\": " + std::to_string(o.trials) + ",\n  \"video\": " + (o.video ? "true" : "false") +
         ",\n  \"still_threshold_rad_s\": " + fmt("%.3f", kStill) + ",\n  \"exit_margin_ms\": " +
         fmt("%.0f", o.margin_ms) + ",\n  \"faults\": [\n";
  for (std::size_t fi = 0; fi < results.size(); ++fi) {
    const auto& r = results[fi];
    const auto& d = *r.def;
    Stats zero, trow, still, reconnect, held;
    std::map<std::string, Stats> det;
    int ok_norestart = 0, ok_tel = 0, ok_vid = 0, injected = 0;
    std::vector<std::string> errors;
    std::map<std::string, int> modes;
    for (const auto& t : r.trials) {
      if (t.injected) ++injected;
      if (t.set_zero_ms) zero.add(*t.set_zero_ms);
      if (t.set_zero_trow_ms) trow.add(*t.set_zero_trow_ms);
      if (t.still_ms) still.add(*t.still_ms);
      for (const auto& [name, val] : t.detect_ms) det[name].add(val);
      if (t.reconnect_ms) reconnect.add(*t.reconnect_ms);
      if (t.injected && t.no_restart) ++ok_norestart, held.add(t.zero_held_after_recovery_s * 1000);
      if (t.telemetry_ok) ++ok_tel;
      if (t.video_ok) ++ok_vid;
      ++modes[t.mode_after.empty() ? "?" : t.mode_after];
      if (!t.error.empty()) errors.push_back("trial " + std::to_string(t.k) + ": " + t.error);
    }
    const bool complete = r.setup_error.empty() && static_cast<int>(r.trials.size()) == o.trials && errors.empty();
    const bool allowed = o.allow_miss.count(d.name) > 0;
    // No trial measured: NaN, which is never within a limit.
    const Judged judged = judge(zero.n() > 0 ? zero.pct(0.99) : NAN, d.target_ms + d.slack_ms, allowed, o);
    const bool met = judged == Judged::kMet;
    std::string verdict = met ? "yes" : "NO" + missLabel(judged, o);
    if (met && zero.pct(0.99) > d.target_ms) verdict = "yes (watchdog tick)";
    std::printf("| %s | %zu | %s | %s | %s | <= %.0f (%s) | %s |\n", d.label, zero.n(), zero.cell().c_str(),
                trow.cell().c_str(), still.cell().c_str(), d.target_ms, d.target_what, verdict.c_str());
    if (!complete) v.ok = false;
    if (judged == Judged::kMissed) v.ok = false;
    for (const auto& e : errors) v.notes.push_back(std::string(d.name) + " " + e);
    if (!r.setup_error.empty()) v.notes.push_back(std::string(d.name) + ": " + r.setup_error);
    // Detection targets.
    for (const auto& dd : d.detectors)
      if (dd.target_ms > 0 && det[dd.name].n() > 0) {
        const double p99 = det[dd.name].pct(0.99);
        const Judged j = judge(p99, dd.target_ms + dd.slack_ms, allowed, o);
        if (j == Judged::kMet) continue;
        if (j == Judged::kMissed) v.ok = false;
        v.notes.push_back(std::string(d.name) + ": " + dd.name + " p99 " + fmt("%.0f", p99) + " ms > target " +
                          fmt("%.0f", dd.target_ms) + " ms" + missLabel(j, o));
      }

    json += std::string("    {\"name\": \"") + d.name + "\", \"label\": \"" + d.label + "\", \"target_ms\": " +
            fmt("%.0f", d.target_ms) + ", \"target_met\": " + (met ? "true" : "false") +
            ", \"trials\": " + std::to_string(r.trials.size()) + ", \"injected\": " + std::to_string(injected) +
            ",\n     \"set_points_zero_ms\": " + zero.json() + ",\n     \"set_points_zero_t_row_ms\": " + trow.json() +
            ",\n     \"wheels_still_ms\": " + still.json() + ",\n     \"detection_ms\": {";
    bool first = true;
    for (const auto& dd : d.detectors) {
      json += std::string(first ? "" : ", ") + "\"" + dd.name + "\": " + det[dd.name].json();
      first = false;
    }
    json += "},\n     \"reconnect_after_recovery_ms\": " + reconnect.json() +
            ",\n     \"no_automatic_restart\": " + std::to_string(ok_norestart) +
            ", \"zero_held_after_recovery_ms\": " + held.json() + ", \"telemetry_restored\": " +
            std::to_string(ok_tel) + ", \"video_restored\": " + std::to_string(ok_vid) + ", \"errors\": [";
    for (std::size_t i = 0; i < errors.size(); ++i) {
      std::string e = errors[i];
      for (auto& c : e)
        if (c == '"' || c == '\\' || c == '\n') c = ' ';
      json += (i ? ", \"" : "\"") + e + "\"";
    }
    json += std::string("]}") + (fi + 1 < results.size() ? ",\n" : "\n");
  }
  json += "  ]\n}\n";

  std::printf("\nDetection (ms from the fault; log lines of robot_client / pc_server, MCU events of the truth log)\n\n");
  std::printf("| fault | detected by | n | p50 / p99 / max | target |\n|---|---|---|---|---|\n");
  for (const auto& r : results) {
    std::map<std::string, Stats> det;
    for (const auto& t : r.trials)
      for (const auto& [name, val] : t.detect_ms) det[name].add(val);
    for (const auto& dd : r.def->detectors)
      std::printf("| %s | %s | %zu | %s | %s |\n", r.def->label, dd.name, det[dd.name].n(), det[dd.name].cell().c_str(),
                  dd.target_ms > 0 ? (fmt("<= %.0f", dd.target_ms) + (dd.slack_ms > 0 ? fmt(" (+%.0f tick)", dd.slack_ms) : "")).c_str() : "");
  }
  std::printf("\nAfter the fault (n trials each): no automatic restart = set-points stayed zero from the stop until the\n"
              "console's next resume + drive (held for at least the time shown after recovery); telemetry = the console's\n"
              "expect connected / telemetry_age < 0.5 / sensor_hz > 50 passed; video = >= 10 fps decoded by the server.\n\n");
  std::printf("| fault | no automatic restart | zero held after recovery, min (s) | mode after | telemetry restored | video restored | link up again after recovery p50 / max (ms) |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (const auto& r : results) {
    int inj = 0, nr = 0, tel = 0, vid = 0;
    Stats held, rc;
    std::map<std::string, int> modes;
    for (const auto& t : r.trials) {
      if (!t.injected) continue;
      ++inj;
      if (t.no_restart) ++nr;
      held.add(t.zero_held_after_recovery_s);
      if (t.telemetry_ok) ++tel;
      if (t.video_ok) ++vid;
      if (t.reconnect_ms) rc.add(*t.reconnect_ms);
      ++modes[t.mode_after.empty() ? "?" : t.mode_after];
    }
    std::string m;
    for (const auto& [k, c] : modes) m += (m.empty() ? "" : ", ") + k + " x" + std::to_string(c);
    std::printf("| %s | %d/%d | %s | %s | %d/%d | %s | %s |\n", r.def->label, nr, inj,
                held.n() ? fmt("%.1f", *std::min_element(held.v.begin(), held.v.end())).c_str() : "-", m.c_str(), tel,
                inj, o.video ? (std::to_string(vid) + "/" + std::to_string(inj)).c_str() : "off",
                rc.n() ? (fmt("%.0f", rc.pct(0.5)) + " / " + fmt("%.0f", rc.max())).c_str() : "- (link stayed up)");
  }
  return v;
}

// ---------------------------------------------------------------- serial bit errors

struct BerResult {
  double ber = 0;
  std::string error;
  // down: MCU -> robot_client sensor frames
  uint64_t down_sent = 0, down_accepted = 0, down_lost = 0, down_foreign = 0;
  // up: robot_client -> MCU wheel commands
  uint64_t up_sent = 0, up_applied = 0, up_lost = 0, up_foreign = 0;
  std::string robot_counters, mcu_counters, relay_down, relay_up;
  double measured_ber_down = 0, measured_ber_up = 0;
  std::size_t down_frame_bytes = 0, up_frame_bytes = 0;
  int failsafes = 0, watchdog_trips = 0;
  double seconds = 0;
};

std::string afterTag(const std::string& text, const std::string& tag) {
  const auto p = text.rfind(tag);
  if (p == std::string::npos) return "";
  const auto e = text.find('\n', p);
  return text.substr(p + tag.size(), e == std::string::npos ? std::string::npos : e - p - tag.size());
}

BerResult runBer(double ber, const Options& o, unsigned seed) {
  BerResult res;
  res.ber = ber;
  Stack s("ber");
  s.measureFailsafes();
  Script sc;
  prologue(sc);
  const int rounds = std::max(1, static_cast<int>(std::ceil(o.ber_seconds / 5.0)));
  for (int i = 0; i < rounds; ++i) {
    sc.add("try resume");  // a sensor timeout (10 frames in a row lost) latches FAILSAFE: go on driving
    sc.add("try drive 0 " + fmt("%.2f", kDriveW));
    sc.add("wait 5");
  }
  sc.add("stop");
  sc.add("wait 0.5");
  if (!s.startServer(sc.text())) {
    res.error = "pc_server did not start\n" + s.logs();
    return res;
  }
  const std::string frames = s.dir() / "frames.csv";
  char b[32];
  std::snprintf(b, sizeof b, "%g", ber);
  // robot_client's frame log is its debug log (INSPECT_LOG=debug): set for the processes of this robot only.
  ::setenv("INSPECT_LOG", "debug", 1);
  auto& r = s.startRobot("robot1", "square_room.yaml",
                         {"--ber-up", b, "--ber-down", b, "--seed", std::to_string(seed), "--garbage-per-s",
                          fmt("%g", o.garbage_per_s)},
                         {"--frame-log", frames});
  ::unsetenv("INSPECT_LOG");
  const int64_t t0 = nowNs();
  const auto rc = s.server().wait(o.ber_seconds + 90);
  res.seconds = ms(nowNs() - t0) / 1000;
  if (!rc) res.error = "the console script did not finish";
  // Final counters: robot_client logs its serial counters on exit, serial_relay and mcu_sim print theirs.
  r.client.terminate();
  s.relay("robot1").terminate();
  r.sim.terminate();

  // (b) Sensor frames: what robot_client accepted vs what mcu_sim sent.
  struct Sent {
    unsigned id, seq, crc;
  };
  std::vector<Sent> sent;
  std::unordered_map<uint32_t, std::size_t> by_time;
  {
    std::istringstream in(readFile(frames));
    std::string line;
    while (std::getline(in, line)) {
      long long mono;
      double t;
      unsigned id, seq, crc, mt;
      if (std::sscanf(line.c_str(), "F,%lld,%lf,%u,%u,%u,%u", &mono, &t, &id, &seq, &crc, &mt) == 6) {
        by_time[mt] = sent.size();
        sent.push_back({id, seq, crc});
      }
    }
  }
  const std::string client_log = readFile(s.dir() / "robot1-client.err");
  std::optional<std::size_t> first, last;
  uint64_t matched = 0;
  {
    std::istringstream in(client_log);
    std::string line;
    while (std::getline(in, line)) {
      const auto p = line.find("rx frame id=");
      if (p == std::string::npos) continue;
      unsigned id, seq, crc, mt;
      if (std::sscanf(line.c_str() + p, "rx frame id=%u seq=%u crc=%u mcu_time_ms=%u", &id, &seq, &crc, &mt) != 4)
        continue;
      ++res.down_accepted;
      const auto it = by_time.find(mt);
      if (it == by_time.end() || sent[it->second].id != id || sent[it->second].seq != seq ||
          sent[it->second].crc != crc || (last && it->second <= *last)) {
        ++res.down_foreign;
        continue;
      }
      ++matched;
      if (!first) first = it->second;
      last = it->second;
    }
  }
  if (first) {
    res.down_sent = *last - *first + 1;
    res.down_lost = res.down_sent - matched;
  }
  // (a) Wheel commands: every C row must be one robot_client sent (its cmd log), in order.
  struct Cmd {
    int seq, l, r, f;
  };
  std::vector<Cmd> cmds;
  {
    std::istringstream in(readFile(r.cmd_log));
    std::string line;
    while (std::getline(in, line)) {
      Cmd c;
      if (std::sscanf(line.c_str(), "%d,%d,%d,%d", &c.seq, &c.l, &c.r, &c.f) == 4) cmds.push_back(c);
    }
  }
  const auto truth = readTruth(r.truth);
  std::size_t j = 0;
  std::optional<std::size_t> cfirst, clast;
  uint64_t cmatched = 0;
  for (const auto& c : truth.commands) {
    std::size_t k = j;
    bool found = false;
    // The next match in order, within the next 256 commands (a sequence number's wrap).
    for (; k < cmds.size() && k < j + 256; ++k)
      if (cmds[k].seq == c.seq && cmds[k].l == c.left && cmds[k].r == c.right && cmds[k].f == c.flags) {
        found = true;
        break;
      }
    ++res.up_applied;
    if (!found) {
      ++res.up_foreign;
      continue;
    }
    ++cmatched;
    if (!cfirst) cfirst = k;
    clast = k;
    j = k + 1;
  }
  if (cfirst) {
    res.up_sent = *clast - *cfirst + 1;
    res.up_lost = res.up_sent - cmatched;
  }
  // Trips once robot_client commands (the one at boot, before it is connected, does not count).
  for (const auto& e : truth.events)
    if (e.name == "watchdog_trip" && !truth.commands.empty() && e.mono_ns > truth.commands.front().mono_ns)
      ++res.watchdog_trips;
  for (std::size_t p = client_log.find("MODE_CHANGE: FAILSAFE"); p != std::string::npos;
       p = client_log.find("MODE_CHANGE: FAILSAFE", p + 1))
    ++res.failsafes;
  res.robot_counters = afterTag(client_log, ": received ");
  const std::string sim_out = readFile(s.dir() / "robot1-sim.out");
  res.mcu_counters = afterTag(sim_out, "mcu_sim: serial ");
  const std::string relay_out = readFile(s.dir() / "robot1-relay.out");
  res.relay_down = afterTag(relay_out, "serial_relay down: ");
  res.relay_up = afterTag(relay_out, "serial_relay up  : ");
  auto measured = [](const std::string& relay) {
    const auto p = relay.find("(BER ");
    return p == std::string::npos ? 0.0 : std::atof(relay.c_str() + p + 5);
  };
  res.measured_ber_down = measured(res.relay_down);
  res.measured_ber_up = measured(res.relay_up);
  inspect::serial::FrameEncoder enc;
  res.down_frame_bytes = enc.encode(inspect::serial::SensorFrame{}).size;
  res.up_frame_bytes = enc.encode(inspect::serial::WheelCommand{}).size;
  if (res.down_accepted < 100 || res.up_applied < 100) res.error += "too few frames (" + std::to_string(res.down_accepted) + " accepted, " + std::to_string(res.up_applied) + " applied)";
  return res;
}

bool printBer(const std::vector<BerResult>& rs, const Options& o, std::string& json) {
  bool ok = true;
  std::printf("\nSerial bit errors between mcu_sim and robot_client (serial_relay --ber-up/--ber-down)");
  if (o.garbage_per_s > 0) std::printf(", and %g bursts of garbage bytes per second each way", o.garbage_per_s);
  std::printf("\n");
  std::printf("lost = frames sent and never accepted (between the first and last accepted); expected = 1-(1-BER)^bits\n"
              "of one frame on the wire; foreign = accepted frames that were not sent unmodified (must be 0)\n\n");
  std::printf("| BER | direction | run (s) | sent | accepted | lost | loss %% | expected %% | foreign |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  json = "{\n  \"garbage_per_s\": " + fmt("%g", o.garbage_per_s) + ",\n  \"ber\": [\n";
  for (std::size_t i = 0; i < rs.size(); ++i) {
    const auto& r = rs[i];
    auto expected = [&](std::size_t bytes, double ber) { return 100.0 * (1.0 - std::pow(1.0 - ber, 8.0 * static_cast<double>(bytes))); };
    const double dl = r.down_sent ? 100.0 * static_cast<double>(r.down_lost) / static_cast<double>(r.down_sent) : 0;
    const double ul = r.up_sent ? 100.0 * static_cast<double>(r.up_lost) / static_cast<double>(r.up_sent) : 0;
    std::printf("| %g | MCU -> Pi sensor frames (%zu B) | %.0f | %llu | %llu | %llu | %.2f | %.2f | %llu |\n", r.ber,
                r.down_frame_bytes, r.seconds, static_cast<unsigned long long>(r.down_sent),
                static_cast<unsigned long long>(r.down_accepted - r.down_foreign),
                static_cast<unsigned long long>(r.down_lost), dl, expected(r.down_frame_bytes, r.ber),
                static_cast<unsigned long long>(r.down_foreign));
    std::printf("| %g | Pi -> MCU wheel commands (%zu B) | %.0f | %llu | %llu | %llu | %.2f | %.2f | %llu |\n", r.ber,
                r.up_frame_bytes, r.seconds, static_cast<unsigned long long>(r.up_sent),
                static_cast<unsigned long long>(r.up_applied - r.up_foreign), static_cast<unsigned long long>(r.up_lost),
                ul, expected(r.up_frame_bytes, r.ber), static_cast<unsigned long long>(r.up_foreign));
    // Frames were damaged both ways (and dropped), none became a wheel command or a sensor frame.
    const bool this_ok = r.error.empty() && r.down_foreign == 0 && r.up_foreign == 0 && r.down_lost > 0 && r.up_lost > 0;
    if (!this_ok) ok = false;
    json += "    {\"ber\": " + fmt("%g", r.ber) + ", \"seconds\": " + fmt("%.1f", r.seconds) +
            ", \"measured_ber_down\": " + fmt("%.3g", r.measured_ber_down) + ", \"measured_ber_up\": " +
            fmt("%.3g", r.measured_ber_up) + ",\n     \"down\": {\"frame_bytes\": " + std::to_string(r.down_frame_bytes) +
            ", \"sent\": " + std::to_string(r.down_sent) + ", \"accepted\": " + std::to_string(r.down_accepted) +
            ", \"lost\": " + std::to_string(r.down_lost) + ", \"foreign\": " + std::to_string(r.down_foreign) +
            "},\n     \"up\": {\"frame_bytes\": " + std::to_string(r.up_frame_bytes) + ", \"sent\": " +
            std::to_string(r.up_sent) + ", \"applied\": " + std::to_string(r.up_applied) + ", \"lost\": " +
            std::to_string(r.up_lost) + ", \"foreign\": " + std::to_string(r.up_foreign) +
            "},\n     \"failsafes\": " + std::to_string(r.failsafes) + ", \"watchdog_trips\": " +
            std::to_string(r.watchdog_trips) + ", \"ok\": " + (this_ok ? "true" : "false") + "}" +
            (i + 1 < rs.size() ? ",\n" : "\n");
  }
  json += "  ]\n}\n";
  std::printf("\nCounters of the programs (receiver's decoder: frames ok and errors by kind)\n\n");
  for (const auto& r : rs) {
    std::printf("BER %g:\n  relay down (MCU -> Pi): %s\n  relay up (Pi -> MCU):   %s\n  robot_client serial: %s\n"
                "  mcu_sim serial: %s\n  robot FAILSAFE latches (sensor timeout): %d, MCU watchdog trips: %d\n",
                r.ber, r.relay_down.c_str(), r.relay_up.c_str(), r.robot_counters.c_str(), r.mcu_counters.c_str(),
                r.failsafes, r.watchdog_trips);
    if (!r.error.empty()) std::printf("  ERROR: %s\n", r.error.c_str());
    if (r.down_lost == 0) std::printf("  ERROR: no sensor frame was lost: were bit errors injected?\n");
    if (r.up_lost == 0) std::printf("  ERROR: no wheel command was lost: were bit errors injected?\n");
  }
  std::printf("\n0 wheel commands derived from corrupted frames: %s (MCU-applied commands not sent by robot_client: %s);\n"
              "0 sensor frames accepted that mcu_sim did not send unmodified: %s\n",
              ok ? "yes" : "NO",
              [&] {
                uint64_t n = 0;
                for (const auto& r : rs) n += r.up_foreign;
                return std::to_string(n);
              }().c_str(),
              [&] {
                uint64_t n = 0;
                for (const auto& r : rs) n += r.down_foreign;
                return n == 0 ? std::string("yes") : "NO (" + std::to_string(n) + ")";
              }().c_str());
  return ok;
}

// Every chosen fault, in the table's order: one after the other with one
// random sequence (--jobs 1), or --jobs at once, each fault on its own stack
// with a random sequence of its own (seed + its place in the table).
std::vector<FaultResult> runFaults(const Options& o) {
  std::vector<const FaultDef*> chosen;
  for (const auto& d : faultDefs())
    if (o.faults.empty() || std::find(o.faults.begin(), o.faults.end(), d.name) != o.faults.end()) chosen.push_back(&d);
  std::vector<FaultResult> results(chosen.size());
  const bool keep = std::getenv("KEEP_TEST_DIRS") != nullptr;
  auto finished = [&](const FaultResult& r) {
    if (keep) std::fprintf(stderr, "fault_inject: %s kept in %s\n", r.def->name, r.dir.c_str());
  };
  if (o.jobs <= 1) {
    std::mt19937 rng(o.seed);
    for (std::size_t i = 0; i < chosen.size(); ++i) {
      std::fprintf(stderr, "fault_inject: %s x %d ", chosen[i]->name, o.trials);
      results[i] = FaultRunner(*chosen[i], o, rng).run();
      finished(results[i]);
    }
    return results;
  }
  std::atomic<std::size_t> next{0};
  std::vector<std::thread> lanes;
  for (int j = 0; j < o.jobs; ++j)
    lanes.emplace_back([&] {
      for (std::size_t i; (i = next.fetch_add(1)) < chosen.size();) {
        std::fprintf(stderr, "fault_inject: %s x %d (lane of %d)\n", chosen[i]->name, o.trials, o.jobs);
        std::mt19937 rng(o.seed + static_cast<unsigned>(i));
        results[i] = FaultRunner(*chosen[i], o, rng).run();
        finished(results[i]);
      }
    });
  for (auto& t : lanes) t.join();
  return results;
}

// ---------------------------------------------------------------- main

constexpr const char* kUsage = R"(usage: fault_inject [options]

Failsafes measured through the real programs (pc_server, robot_client, mcu_sim):
each fault N times, fault -> wheels at zero from the simulator's ground truth,
detection from the programs' logs, no automatic restart, recovery of telemetry
and video. docs/failsafes.md.

options:
  --trials N          trials per fault (default 30)
  --faults LIST       comma-separated subset of: server_sigkill, server_sigstop, client_sigkill,
                      client_sigstop, serial_cut, telemetry_stale, sensor_stale (default: all)
  --hold S            how long each fault lasts before recovery, s (default 1.3)
  --no-video          robots without the camera stream (video is checked after recovery otherwise)
  --allow-miss LIST   faults whose timing target may be missed without failing (known, reported)
  --margin-ms M       a p99 over its target by at most M ms does not fail the run (reported as NO
                      all the same); for ctest on shared machines (default 0)
  --ber               instead: the serial bit-error test
  --ber-rates LIST    bit error rates (default 1e-4,1e-3)
  --ber-seconds S     seconds per rate (default 45)
  --garbage-per-s N   with --ber: also bursts of 1-24 random bytes per second each way (default 0)
  --json FILE         write the figures as JSON
  --seed N            random seed (fault timing, bit errors; default 1)
  --jobs N            faults run at once, each on a stack of its own (default 1: the measurement;
                      ctest's short form runs all 7 at once)
  --firmware ELF      the MCU is the real firmware: its QEMU image under scripts/mcu_qemu.sh with
                      mcu_sim --hil (docs/firmware.md); the set-points in the ground truth are the
                      firmware's (100 Hz T rows). Not with --ber
  --verbose           progress and logs of failed trials on stderr
  --help

Exit status: 0 all checks passed and targets met (or allowed), 1 otherwise, 2 bad usage.
KEEP_TEST_DIRS=1 keeps the programs' logs and truth files (the directories are printed).
)";

}  // namespace

int main(int argc, char** argv) {
  Options o;
  inspect::cli::readOrExit("fault_inject", argc, argv, [&](inspect::cli::ArgReader& a) {
    if (a.isHelp()) {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else if (a.is("--trials")) {
      o.trials = static_cast<int>(a.integer(1, 10000));
    } else if (a.is("--faults")) {
      o.faults = a.list();
      for (const auto& f : o.faults)
        if (std::none_of(faultDefs().begin(), faultDefs().end(), [&](const FaultDef& d) { return f == d.name; }))
          a.fail("unknown fault '" + f + "'");
    } else if (a.is("--allow-miss")) {
      for (const auto& f : a.list()) o.allow_miss.insert(f);
    } else if (a.is("--margin-ms")) {
      o.margin_ms = a.number(0, 10000);
    } else if (a.is("--hold")) {
      o.hold_s = a.number(0.5, 30);
    } else if (a.is("--no-video")) {
      o.video = false;
    } else if (a.is("--ber")) {
      o.ber = true;
    } else if (a.is("--ber-rates")) {
      o.ber_rates.clear();
      for (const auto& r : a.list()) {
        char* end = nullptr;
        const double d = std::strtod(r.c_str(), &end);
        if (*end || !(d > 0 && d <= 0.5)) a.fail("'" + r + "' is not a rate in (0, 0.5]");
        o.ber_rates.push_back(d);
      }
    } else if (a.is("--ber-seconds")) {
      o.ber_seconds = a.number(5, 3600);
    } else if (a.is("--garbage-per-s")) {
      o.garbage_per_s = a.number(0, 1000);
    } else if (a.is("--json")) {
      o.json = a.path();
    } else if (a.is("--seed")) {
      o.seed = static_cast<unsigned>(a.integer(0, 4294967295LL));
    } else if (a.is("--verbose")) {
      o.verbose = true;
    } else if (a.is("--jobs")) {
      o.jobs = static_cast<int>(a.integer(1, 7));
    } else if (a.is("--firmware")) {
      o.firmware = a.path();
    } else {
      a.unknown();
    }
  });
  if (o.ber && !o.firmware.empty()) {
    std::fprintf(stderr, "fault_inject: --firmware: not with --ber (its check reads the emulator's C rows)\n");
    return 2;
  }
  std::signal(SIGPIPE, SIG_IGN);
  std::string json;
  bool ok = true;
  if (o.ber) {
    std::vector<BerResult> rs;
    unsigned seed = o.seed;
    for (double b : o.ber_rates) {
      std::fprintf(stderr, "fault_inject: BER %g for %.0f s ...\n", b, o.ber_seconds);
      rs.push_back(runBer(b, o, seed++));
    }
    ok = printBer(rs, o, json);
  } else {
    const std::vector<FaultResult> results = runFaults(o);
    const Verdict v = printFaults(results, o, json);
    ok = v.ok;
    if (!v.notes.empty()) {
      std::printf("\nNotes:\n");
      for (const auto& n : v.notes) std::printf("- %s\n", n.c_str());
    }
  }
  if (!o.json.empty()) {
    std::ofstream(o.json) << json;
  }
  std::printf("\nfault_inject: %s\n", ok ? "PASS" : "FAIL");
  return ok ? 0 : 1;
}
