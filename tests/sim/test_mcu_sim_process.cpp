// The real mcu_sim program: command line errors, and one run on a real pty
// driven like robot_client would drive it (frames in, wheel commands out,
// watchdog when the commands stop). Every wait is bounded; the child is
// killed on every path.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "shared/serial/frame_codec.hpp"
#include "shared/util/clock.hpp"
#include "tests/support/paths.hpp"
#include "tests/support/stack.hpp"

using namespace inspect;

namespace {

const std::string kBin = inspect::test::binPath("mcu_sim");

struct Captured {
  int exit_code = -1;
  std::string out;  // stdout + stderr
};

// Runs mcu_sim to completion with a time limit; for quick command line checks.
Captured runQuick(const std::string& args) {
  Captured c;
  const std::string cmd = "timeout 10 " + kBin + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return c;
  char buf[512];
  while (std::fgets(buf, sizeof buf, p)) c.out += buf;
  const int st = pclose(p);
  c.exit_code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return c;
}

// A child mcu_sim with its stdout on a pipe; killed and reaped on destruction.
class SimProcess {
 public:
  explicit SimProcess(const std::vector<std::string>& args) {
    int fds[2];
    if (pipe(fds) != 0) return;
    pid_ = fork();
    if (pid_ == 0) {
      dup2(fds[1], STDOUT_FILENO);
      close(fds[0]);
      close(fds[1]);
      std::vector<char*> argv;
      argv.push_back(const_cast<char*>(kBin.c_str()));
      for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      execv(kBin.c_str(), argv.data());
      _exit(127);
    }
    close(fds[1]);
    out_fd_ = fds[0];
  }
  ~SimProcess() {
    if (pid_ > 0 && !reaped_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    if (out_fd_ >= 0) close(out_fd_);
  }
  bool started() const { return pid_ > 0 && out_fd_ >= 0; }
  pid_t pid() const { return pid_; }

  /// Next stdout line, or "" after timeout_ms.
  std::string readLine(int timeout_ms) {
    const int64_t end = monoNowNs() + int64_t{timeout_ms} * 1000000;
    for (;;) {
      if (const auto nl = buf_.find('\n'); nl != std::string::npos) {
        std::string line = buf_.substr(0, nl);
        buf_.erase(0, nl + 1);
        return line;
      }
      const int64_t left_ms = (end - monoNowNs()) / 1000000;
      if (left_ms <= 0) return "";
      pollfd p{out_fd_, POLLIN, 0};
      if (poll(&p, 1, static_cast<int>(left_ms)) <= 0) continue;
      char tmp[512];
      const ssize_t n = read(out_fd_, tmp, sizeof tmp);
      if (n <= 0) return "";
      buf_.append(tmp, static_cast<std::size_t>(n));
    }
  }
  /// Waits up to timeout_ms for exit; returns the exit code or -1.
  int wait(int timeout_ms) {
    const int64_t end = monoNowNs() + int64_t{timeout_ms} * 1000000;
    while (monoNowNs() < end) {
      int st = 0;
      if (waitpid(pid_, &st, WNOHANG) == pid_) {
        reaped_ = true;
        return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return -1;
  }

 private:
  pid_t pid_ = -1;
  int out_fd_ = -1;
  bool reaped_ = false;
  std::string buf_;
};

class TempDir {
 public:
  TempDir() {
    char tmpl[] = "/tmp/sim_test_XXXXXX";
    if (mkdtemp(tmpl)) path_ = tmpl;
  }
  ~TempDir() {
    if (!path_.empty()) std::system(("rm -rf '" + path_ + "'").c_str());
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

int openRawSerial(const std::string& path) {
  const int fd = open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  if (fd < 0) return -1;
  termios t{};
  tcgetattr(fd, &t);
  cfmakeraw(&t);
  tcsetattr(fd, TCSANOW, &t);
  tcflush(fd, TCIFLUSH);  // frames queued before we opened are stale
  return fd;
}

std::vector<std::vector<std::string>> readCsv(const std::string& path) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> cols;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) cols.push_back(c);
    rows.push_back(cols);
  }
  return rows;
}

}  // namespace

TEST(McuSimProgram, HelpAndCommandLineErrors) {
  const auto help = runQuick("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("--pty-link"), std::string::npos) << help.out;

  const auto bad_flag = runQuick("--world x.yaml --frobnicate");
  EXPECT_EQ(bad_flag.exit_code, 2);
  EXPECT_EQ(bad_flag.out, "mcu_sim: --frobnicate: unknown option (see --help)\n");

  const auto bad_rate = runQuick("--world x.yaml --rate 1000");
  EXPECT_EQ(bad_rate.exit_code, 2);
  EXPECT_NE(bad_rate.out.find("--rate"), std::string::npos);

  const auto missing = runQuick("--world /nonexistent.yaml --robot " + inspect::test::srcPath("config/robot.yaml"));
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.out.find("/nonexistent.yaml"), std::string::npos) << missing.out;
}

TEST(McuSimProgram, BadWorldFileIsOneLineNamingFileAndKey) {
  TempDir dir;
  const std::string world = dir.path() + "/bad.yaml";
  std::ofstream(world) << "name: bad\nwals: []\n";
  const auto r = runQuick("--world " + world + " --robot " + inspect::test::srcPath("config/robot.yaml --duration 1"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.out, "mcu_sim: " + world + ": wals: unknown key (misspelt, or not used by this program)\n");
}

TEST(McuSimProgram, RealPtyFramesCommandsAndWatchdog) {
  TempDir dir;
  ASSERT_FALSE(dir.path().empty());
  const std::string link = dir.path() + "/mcu";
  const std::string truth = dir.path() + "/truth.csv";
  constexpr double kRate = 5.0;
  // 6 s of sim time = 1.2 s of wall time: room for the three phases below on a busy machine.
  SimProcess sim({"--world", inspect::test::srcPath("config/worlds/empty.yaml"), "--robot", inspect::test::srcPath("config/robot.yaml"), "--rate", "5",
                  "--duration", "6", "--pty-link", link, "--truth", truth});
  ASSERT_TRUE(sim.started());
  const std::string dev_line = sim.readLine(5000);
  ASSERT_EQ(dev_line.rfind("mcu_sim: serial device /dev/pts/", 0), 0u) << dev_line;
  const std::string device = dev_line.substr(std::string("mcu_sim: serial device ").size());
  ASSERT_EQ(sim.readLine(1000), "mcu_sim: linked at " + link);
  char target[256] = {};
  ASSERT_GT(readlink(link.c_str(), target, sizeof target - 1), 0);
  EXPECT_EQ(std::string(target), device);

  const int fd = openRawSerial(link);
  ASSERT_GE(fd, 0) << link;
  serial::FrameDecoder dec;
  std::vector<serial::SensorFrame> frames;
  // (wall ns, mcu_time_ms) of the newest frame of each read: that frame left
  // the simulator just before it was read, however late this thread was.
  std::vector<std::pair<int64_t, uint32_t>> newest;
  auto drain = [&] {
    uint8_t buf[1024];
    const std::size_t before = frames.size();
    for (int i = 0; i < 100; ++i) {
      const ssize_t n = read(fd, buf, sizeof buf);
      if (n <= 0) break;
      dec.feed(std::span<const uint8_t>(buf, static_cast<std::size_t>(n)), [&](const serial::Message& m, uint8_t) {
        if (auto* s = std::get_if<serial::SensorFrame>(&m)) frames.push_back(*s);
      });
    }
    if (frames.size() > before) newest.emplace_back(monoNowNs(), frames.back().mcu_time_ms);
  };
  auto pollFor = [&](int ms) {
    pollfd p{fd, POLLIN, 0};
    poll(&p, 1, ms);
    drain();
  };

  // Phase 1: ~1 s of sim time (0.2 s wall) of sensor frames.
  const int64_t t1 = monoNowNs();
  while (monoNowNs() - t1 < 200'000'000) pollFor(20);
  const double wall1_s = static_cast<double>(monoNowNs() - t1) / 1e9;
  const double frames_per_wall_s = static_cast<double>(frames.size()) / wall1_s;
  ASSERT_GE(frames.size(), 2u);
  ASSERT_GE(newest.size(), 2u);
  const uint32_t span_ms = frames.back().mcu_time_ms - frames.front().mcu_time_ms;
  // The rate: sim time against wall time between the newest frames of the
  // first and the last read (a count of frames in the window would also count
  // a stall of either process at its ends).
  const double rate_measured = (newest.back().second - newest.front().second) / 1000.0 /
                               (static_cast<double>(newest.back().first - newest.front().first) / 1e9);
  std::printf("[ measured ] %zu frames in %.3f s wall = %.0f frames/s (expect %.0f); mcu_time span %u ms; "
              "sim/wall rate %.2f\n",
              frames.size(), wall1_s, frames_per_wall_s, 100.0 * kRate, span_ms, rate_measured);
  EXPECT_NEAR(rate_measured, kRate, 0.3 * kRate);
  EXPECT_EQ(frames.size(), span_ms / 10 + 1u) << "frames lost or duplicated";
  EXPECT_EQ(dec.counters().errors(), 0u);
  EXPECT_EQ(dec.counters().seq_gaps, 0u);
  const std::size_t frames_before_cmds = frames.size();

  // Phase 2: wheel commands (0.5 m/s ahead) every 4 ms wall (20 ms sim) for 1 s of sim time.
  serial::FrameEncoder enc;
  int64_t last_send_ns = 0;
  int sent = 0;
  const int64_t t2 = monoNowNs();
  while (monoNowNs() - t2 < 200'000'000) {
    const auto f = enc.encode(serial::WheelCommand{2500, 2500, serial::WheelCommand::kEnable});
    last_send_ns = monoNowNs();  // before the write: the MCU cannot have it earlier
    ASSERT_EQ(write(fd, f.bytes.data(), f.size), static_cast<ssize_t>(f.size));
    ++sent;
    pollFor(4);
  }
  EXPECT_GT(sent, 20);
  ASSERT_GT(frames.size(), frames_before_cmds);
  int frames_driving = 0;  // frames while the commands kept the watchdog clear
  for (std::size_t i = frames_before_cmds; i < frames.size(); ++i)
    frames_driving += (frames[i].faults & serial::kFaultWatchdog) == 0;
  EXPECT_GT(frames_driving, 20);

  // Phase 3: silence; the MCU must stop the wheels by itself after 200 ms of sim time.
  // (If this process was starved during phase 2 the watchdog may also have
  // tripped and cleared in between; the trip that counts follows the last command.)
  std::vector<std::string> trip;
  const int64_t t3 = monoNowNs();
  while (trip.empty() && monoNowNs() - t3 < 1'000'000'000) {
    pollFor(10);
    const auto rows = readCsv(truth);
    double last_cmd_sim_s = -1.0;
    for (const auto& row : rows)
      if (row.size() >= 3 && row[0] == "C") last_cmd_sim_s = std::stod(row[2]);
    for (const auto& row : rows) {
      if (row.size() >= 5 && row[0] == "E" && row[3] == "watchdog_trip" && last_cmd_sim_s >= 0 &&
          std::stod(row[2]) > last_cmd_sim_s) {
        trip = row;
        break;
      }
    }
  }
  ASSERT_FALSE(trip.empty()) << "no watchdog_trip after the last command";
  const int trip_ms = std::stoi(trip[4]);
  EXPECT_LE(trip_ms, 201);
  EXPECT_GE(trip_ms, 200);
  const double latency_wall_ms = static_cast<double>(std::stoll(trip[1]) - last_send_ns) / 1e6;
  std::printf("[ measured ] watchdog_trip detail %d ms sim; %.1f ms wall after the last command was written "
              "(200 ms sim / rate %.0f = %.0f ms)\n",
              trip_ms, latency_wall_ms, kRate, 200.0 / kRate);
  EXPECT_GT(latency_wall_ms, 0.8 * 200.0 / kRate);
  EXPECT_LT(latency_wall_ms, 200.0 / kRate + 250.0);  // 40 ms + room for a shared machine (the sim-time figure is exact)

  close(fd);

  // The run ends by itself after --duration with the final pose and the serial statistics.
  EXPECT_EQ(sim.wait(5000), 0);
  const std::string pose = sim.readLine(1000);
  EXPECT_EQ(pose.rfind("mcu_sim: final pose x=", 0), 0u) << pose;
  const std::string stats = sim.readLine(1000);
  EXPECT_NE(stats.find("utilisation"), std::string::npos) << stats;
  std::printf("[ measured ] %s\n", stats.c_str());

  // Ground truth (complete now): the robot drove forward (about 0.5 m/s for 1 s of sim time, minus the motor lag).
  double x_end = 0.0;
  int commands_logged = 0;
  int rows_after_trip = 0;
  for (const auto& row : readCsv(truth)) {
    if (row[0] == "T" && row.size() == 11) {
      x_end = std::stod(row[3]);
      EXPECT_NEAR(std::stod(row[4]), 0.0, 1e-6);
      if (std::stod(row[2]) >= std::stod(trip[2])) {  // after the trip: set-points zero, fault flag set
        ++rows_after_trip;
        EXPECT_EQ(std::stod(row[8]), 0.0) << row[2];
        EXPECT_EQ(std::stod(row[9]), 0.0) << row[2];
        EXPECT_EQ(std::stoi(row[10]) & serial::kFaultWatchdog, serial::kFaultWatchdog) << row[2];
      }
    }
    if (row[0] == "C") {
      ++commands_logged;
      EXPECT_EQ(row.size(), 7u);
      EXPECT_EQ(row[4], "2500");
      EXPECT_EQ(row[6], "1");
    }
  }
  EXPECT_EQ(commands_logged, sent);
  EXPECT_GT(rows_after_trip, 0);
  EXPECT_GT(x_end, 0.2);
  EXPECT_LT(x_end, 0.7);
  struct stat st{};
  EXPECT_NE(lstat(link.c_str(), &st), 0) << "the --pty-link symlink was not removed";
  const auto rows = readCsv(truth);
  ASSERT_FALSE(rows.empty());
  EXPECT_EQ(rows.back()[3], "stop");
}

TEST(McuSimProgram, SigtermPrintsFinalPoseAndCleansUp) {
  TempDir dir;
  const std::string link = dir.path() + "/mcu";
  SimProcess sim({"--world", inspect::test::srcPath("config/worlds/square_room.yaml"), "--robot", inspect::test::srcPath("config/robot.yaml"),
                  "--pty-link", link});
  ASSERT_TRUE(sim.started());
  ASSERT_EQ(sim.readLine(5000).rfind("mcu_sim: serial device ", 0), 0u);
  ASSERT_EQ(sim.readLine(1000), "mcu_sim: linked at " + link);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  kill(sim.pid(), SIGTERM);
  EXPECT_EQ(sim.wait(3000), 0);
  EXPECT_EQ(sim.readLine(1000), "mcu_sim: final pose x=2.0000 y=4.0000 theta=0.0000");
  struct stat st{};
  EXPECT_NE(lstat(link.c_str(), &st), 0);
}

namespace {
// mcu_sim stopped for `stall_ms` of wall time half-way through 1 s of sim
// time; returns the wall time its truth log spans minus the sim time.
double wallMinusSimAfterStall(bool freeze, int stall_ms, std::string& err) {
  TempDir dir;
  const std::string truth = dir.path() + "/truth.csv", err_path = dir.path() + "/sim.err";
  std::vector<std::string> args = {"--world", inspect::test::srcPath("config/worlds/empty.yaml"), "--robot",
                                   inspect::test::srcPath("config/robot.yaml"), "--truth", truth, "--duration", "1"};
  if (freeze) args.push_back("--freeze-on-stall");
  // stderr to a file: the stall's line.
  const int saved = dup(STDERR_FILENO);
  const int fd = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  dup2(fd, STDERR_FILENO);
  SimProcess sim(args);
  dup2(saved, STDERR_FILENO);
  ::close(fd);
  ::close(saved);
  if (!sim.started()) return -1;
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  kill(sim.pid(), SIGSTOP);
  std::this_thread::sleep_for(std::chrono::milliseconds(stall_ms));
  kill(sim.pid(), SIGCONT);
  if (sim.wait(5000) != 0) return -1;
  err = inspect::test::readFile(err_path);
  const auto t = inspect::test::readTruth(truth);
  if (t.rows.size() < 2) return -1;
  return static_cast<double>(t.rows.back().mono_ns - t.rows.front().mono_ns) * 1e-9 -
         (t.rows.back().t - t.rows.front().t);
}
}  // namespace

TEST(McuSimProgram, FreezeOnStallPausesTheWorldInsteadOfCatchingUp) {
  std::string err;
  // Caught up: the truth log's sim time keeps up with the wall clock.
  const double caught_up = wallMinusSimAfterStall(false, 400, err);
  EXPECT_GE(caught_up, -0.05) << err;
  EXPECT_LT(caught_up, 0.15) << err;
  EXPECT_NE(err.find("mcu_sim: not run for"), std::string::npos) << err;
  // Frozen: the 400 ms stall is missing from sim time.
  const double frozen = wallMinusSimAfterStall(true, 400, err);
  EXPECT_GT(frozen, 0.3) << err;
  EXPECT_LT(frozen, 0.6) << err;
  EXPECT_NE(err.find("; the world waited"), std::string::npos) << err;
}
