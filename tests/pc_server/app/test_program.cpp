// The real pc_server binary: script mode with a test robot, piped stdin,
// exit statuses, config errors and shutdown by signal.
#include <algorithm>
#include <gtest/gtest.h>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/support/fake_robot/scripted_robot.hpp"
#include "tests/support/paths.hpp"

using namespace inspect;
using namespace inspect::test;
namespace fs = std::filesystem;

namespace {

const std::string kBinary = inspect::test::binPath("pc_server");
const std::string kConfig = inspect::test::srcPath("config/server.yaml");

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// pc_server as a child process; stdout/stderr go to files, stdin from a file or /dev/null.
class Program {
 public:
  explicit Program(const std::string& name) : dir_(fs::temp_directory_path() / ("pc_server_test_" + name + "_" +
                                                                               std::to_string(::getpid()))) {
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~Program() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    if (pty_ >= 0) ::close(pty_);
    fs::remove_all(dir_);
  }

  fs::path file(const std::string& name, const std::string& text) const {
    const auto p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }
  fs::path path(const std::string& name) const { return dir_ / name; }

  static std::vector<std::string> withDefaults(std::vector<std::string> args) {
    // No UDP video port 5600 (tests run in parallel); the video tests ask for an ephemeral one.
    if (std::find(args.begin(), args.end(), "--video-port") == args.end()) args.push_back("--no-video");
    // Nor the Foxglove bridge's TCP port 8765 and a token file in the working directory.
    if (std::find(args.begin(), args.end(), "--foxglove-port") == args.end()) args.push_back("--no-foxglove");
    // Nor a catalog in the working directory.
    if (std::find(args.begin(), args.end(), "--runs-dir") == args.end()) args.push_back("--no-record");
    // Mutual TLS with the tests' certificates unless the test says otherwise.
    if (std::find(args.begin(), args.end(), "--plaintext") == args.end() &&
        std::find(args.begin(), args.end(), "--certs") == args.end()) {
      args.push_back("--certs");
      args.push_back(testCertsDir());
    }
    args.insert(args.begin(), kBinary);
    return args;
  }

  [[noreturn]] static void exec(std::vector<std::string>& args) {
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(kBinary.c_str(), argv.data());
    ::_exit(127);
  }

  void start(std::vector<std::string> args, const std::string& stdin_text = "") {
    const auto in_path = file("stdin.txt", stdin_text);
    const auto out_path = path("stdout.txt");
    const auto err_path = path("stderr.txt");
    args = withDefaults(std::move(args));
    pid_ = ::fork();
    ASSERT_GE(pid_, 0);
    if (pid_ == 0) {
      const int in = ::open(in_path.c_str(), O_RDONLY);
      const int out = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int err = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(in, 0);
      ::dup2(out, 1);
      ::dup2(err, 2);
      exec(args);
    }
  }

  /// Starts it on a pseudo-terminal (stdin, stdout and stderr; 100 x 30), as
  /// an operator's terminal: ptyWrite types, ptyReadUntil reads the screen's bytes.
  void startOnPty(std::vector<std::string> args) {
    args = withDefaults(std::move(args));
    pty_ = ::posix_openpt(O_RDWR | O_NOCTTY);
    ASSERT_GE(pty_, 0);
    ASSERT_EQ(::grantpt(pty_), 0);
    ASSERT_EQ(::unlockpt(pty_), 0);
    const std::string slave = ::ptsname(pty_);
    winsize ws{};
    ws.ws_row = 30;
    ws.ws_col = 100;
    ::ioctl(pty_, TIOCSWINSZ, &ws);
    pid_ = ::fork();
    ASSERT_GE(pid_, 0);
    if (pid_ == 0) {
      ::setsid();
      const int fd = ::open(slave.c_str(), O_RDWR);  // the controlling terminal
      ::dup2(fd, 0);
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      exec(args);
    }
  }

  void ptyWrite(const std::string& keys) { ASSERT_EQ(::write(pty_, keys.data(), keys.size()), static_cast<ssize_t>(keys.size())); }

  /// Reads the terminal until `needle` appears after what was read before, up
  /// to `timeout`; true when it did. ptyText() has all that was read.
  bool ptyReadUntil(const std::string& needle, std::chrono::milliseconds timeout = 5000ms) {
    const std::size_t from = pty_seen_;
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline) {
      if (const auto at = pty_text_.find(needle, from); at != std::string::npos) {
        pty_seen_ = at + needle.size();
        return true;
      }
      pollfd p{pty_, POLLIN, 0};
      if (::poll(&p, 1, 20) <= 0) continue;
      char buf[4096];
      const auto n = ::read(pty_, buf, sizeof buf);
      if (n <= 0) return false;  // the program closed the terminal
      pty_text_.append(buf, static_cast<std::size_t>(n));
    }
    return false;
  }
  const std::string& ptyText() const { return pty_text_; }

  /// The port from --port-file, waiting up to 5 s for the file.
  uint16_t waitPort(const fs::path& port_file) {
    const auto deadline = Clock::now() + 5s;
    while (Clock::now() < deadline) {
      if (fs::exists(port_file)) return static_cast<uint16_t>(std::stoi(slurp(port_file)));
      std::this_thread::sleep_for(10ms);
    }
    return 0;
  }

  /// Exit status, or -1 if it did not exit within `timeout`.
  int wait(std::chrono::milliseconds timeout = 10000ms) {
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline) {
      int st = 0;
      if (::waitpid(pid_, &st, WNOHANG) == pid_) {
        pid_ = -1;
        return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
      }
      std::this_thread::sleep_for(10ms);
    }
    return -1;
  }

  void signal(int sig) { ::kill(pid_, sig); }
  std::string out() const { return slurp(dir_ / "stdout.txt"); }
  std::string err() const { return slurp(dir_ / "stderr.txt"); }

 private:
  fs::path dir_;
  pid_t pid_ = -1;
  int pty_ = -1;
  std::string pty_text_;
  std::size_t pty_seen_ = 0;
};

#define EXPECT_HAS(text, part) EXPECT_NE((text).find(part), std::string::npos) << (text)

}  // namespace

TEST(Program, ScriptWithARobotPasses) {
  Program p("script_ok");
  const auto script = p.file("s.txt",
                             "# waits for the test robot\n"
                             "expect robots >= 1 within 5\n"
                             "expect connected == 1\n"
                             "\n"
                             "expect x > 3 within 2\n"
                             "drive 0.2 0\n"
                             "expect telemetry_hz > 10 within 2\n"
                             "stop\n"
                             "estop\n"
                             "robots\n"
                             "echo all done\n");
  const auto port_file = p.path("port");
  p.start({"--config", kConfig, "--bind", "127.0.0.1", "--port", "0", "--port-file", port_file.string(), "--script",
           script.string()});
  const uint16_t port = p.waitPort(port_file);
  ASSERT_GT(port, 0);
  ScriptedRobot r;
  ASSERT_TRUE(r.connect(port));
  ASSERT_TRUE(r.hello("robot1"));
  r.startPump(50);
  const int rc = p.wait();
  const auto out = p.out();
  EXPECT_EQ(rc, 0) << out << p.err();
  EXPECT_HAS(out, "pc_server: listening on 127.0.0.1:" + std::to_string(port));
  EXPECT_HAS(out, "[2] expect robots >= 1 within 5");
  EXPECT_HAS(out, "selected robot1 (the first robot to connect)");
  EXPECT_HAS(out, "expect ok (line 3): connected = 1");
  EXPECT_HAS(out, "robot1: drive +0.20 m/s +0.00 rad/s accepted");
  EXPECT_HAS(out, "robot1: stop accepted");
  EXPECT_HAS(out, "robot1: estop accepted");
  EXPECT_HAS(out, "all done");
  EXPECT_HAS(out, "0 failed, 0 errors");
  r.stopPump();
  int teleops = 0;
  for (const auto& m : r.received()) teleops += m.env.has_command() && m.env.command().has_teleop();
  EXPECT_GE(teleops, 1);
}

TEST(Program, FailedExpectExitsWithOne) {
  Program p("script_fail");
  const auto script = p.file("s.txt", "echo start\nexpect robots >= 1 within 0.2\necho still runs\n");
  p.start({"--config", kConfig, "--bind", "127.0.0.1", "--port", "0", "--script", script.string()});
  EXPECT_EQ(p.wait(), 1);
  const auto out = p.out();
  EXPECT_HAS(out, "EXPECT FAILED (line 2): robots = 0, wanted >= 1 within 0.2 s");
  EXPECT_HAS(out, "still runs");
}

TEST(Program, CommandErrorExitsWithOne) {
  Program p("script_error");
  const auto script = p.file("s.txt", "drvie 1 0\n");
  p.start({"--config", kConfig, "--port", "0", "--bind", "127.0.0.1", "--script", script.string()});
  EXPECT_EQ(p.wait(), 1);
  EXPECT_HAS(p.out(), "unknown command 'drvie' (try 'help')");
}

TEST(Program, PipedStdinRunsLikeAScript) {
  Program p("stdin");
  p.start({"--config", kConfig, "--bind", "127.0.0.1", "--port", "0"}, "echo hi\nexpect robots == 0\n");
  EXPECT_EQ(p.wait(), 0) << p.out() << p.err();
  EXPECT_HAS(p.out(), "[1] echo hi");
  EXPECT_HAS(p.out(), "expect ok (line 2): robots = 0");
}

TEST(Program, OnATerminalTheConsoleEditsCompletesAndRecalls) {
  Program p("pty");
  p.startOnPty({"--config", kConfig, "--bind", "127.0.0.1", "--port", "0", "--plaintext"});
  ASSERT_TRUE(p.ptyReadUntil("\n> ")) << p.ptyText();
  p.ptyWrite("help dri\t\r");  // Tab completes the command name after help
  EXPECT_TRUE(p.ptyReadUntil("drive <v_m_s> <w_rad_s>")) << p.ptyText();
  p.ptyWrite("tune s\t");  // seed=, seeds=, speed=, start=: listed
  EXPECT_TRUE(p.ptyReadUntil("seed=  seeds=  speed=  start=")) << p.ptyText();
  p.ptyWrite("\x15" "echo 1x\x02\x7f" "2\r");  // Ctrl-U, type, Left, Backspace, "2": "echo 2x"
  EXPECT_TRUE(p.ptyReadUntil("\n2x")) << p.ptyText();
  p.ptyWrite("\x1b[A\x1b[D\x1b[D3\r");  // Up recalls "echo 2x"; edited in the middle
  EXPECT_TRUE(p.ptyReadUntil("\n32x")) << p.ptyText();
  p.ptyWrite("\x04");  // Ctrl-D on an empty line leaves
  EXPECT_EQ(p.wait(), 0) << p.ptyText();
}

TEST(Program, AnUnreachableCatalogIsOneLineNamingItAndExitThree) {
  Program p("catalog_down");
  // Port 1 on loopback: nothing listens there; the password comes from the environment, not the URL.
  p.start({"--config", kConfig, "--bind", "127.0.0.1", "--port", "0", "--runs-dir", p.path("runs").string(),
           "--catalog", "postgresql://fleet@127.0.0.1:1/inspect?connect_timeout=2", "--no-console"});
  EXPECT_EQ(p.wait(), 3) << p.out() << p.err();  // a start-up failure, as a port that cannot be bound
  const std::string err = p.err();
  EXPECT_HAS(err, "pc_server: recording: catalog postgresql://fleet@127.0.0.1:1/inspect?connect_timeout=2: "
                  "cannot connect: ");
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
}

TEST(Program, BadConfigIsOneLineAndExitTwo) {
  Program p("bad_config");
  const auto cfg = p.file("server.yaml", "port: 7600\nsession_timeout_s: -1\n");
  p.start({"--config", cfg.string(), "--port", "0"});
  EXPECT_EQ(p.wait(), 2);
  const auto err = p.err();
  EXPECT_HAS(err, cfg.string() + ": session_timeout_s: -1 is out of range");
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
}

TEST(Program, BadFlagExitsTwoAndHelpExitsZero) {
  Program bad("bad_flag");
  bad.start({"--porrt", "1"});
  EXPECT_EQ(bad.wait(), 2);
  EXPECT_HAS(bad.err(), "pc_server: --porrt: unknown option (see --help)");
  Program help("help");
  help.start({"--help"});
  EXPECT_EQ(help.wait(), 0);
  EXPECT_HAS(help.out(), "--no-console");
}

TEST(Program, NoConsoleServesUntilSigterm) {
  Program p("no_console");
  const auto port_file = p.path("port");
  p.start({"--config", kConfig, "--bind", "127.0.0.1", "--port", "0", "--port-file", port_file.string(),
           "--no-console"});
  const uint16_t port = p.waitPort(port_file);
  ASSERT_GT(port, 0);
  ScriptedRobot r;
  ASSERT_TRUE(r.connect(port));
  ASSERT_TRUE(r.hello("robot1"));
  r.startPump(20);
  std::this_thread::sleep_for(200ms);
  p.signal(SIGTERM);
  EXPECT_EQ(p.wait(3000ms), 0);
  r.stopPump();
  EXPECT_TRUE(r.waitClosed(1000ms));
}

TEST(Program, SigintInterruptsAScript) {
  Program p("sigint");
  const auto script = p.file("s.txt", "wait 30\n");
  const auto port_file = p.path("port");
  p.start({"--config", kConfig, "--bind", "127.0.0.1", "--port", "0", "--port-file", port_file.string(), "--script",
           script.string()});
  ASSERT_GT(p.waitPort(port_file), 0);
  std::this_thread::sleep_for(100ms);
  const auto t0 = Clock::now();
  p.signal(SIGINT);
  EXPECT_EQ(p.wait(3000ms), 1);
  EXPECT_LT(Clock::now() - t0, 2s);
  EXPECT_HAS(p.out(), "interrupted");
}

TEST(Program, SigintDuringTuneCancelsItKeepingTheBestAndTheScriptGoesOn) {
  Program p("sigint_tune");
  // 100000 evaluations would take an hour: only Ctrl-C ends it.
  const auto script = p.file("s.txt", "tune evals=100000 variations=1 seeds=1 threads=1\necho after the tune\ngains show\ntune list\n");
  const auto port_file = p.path("port");
  p.start({"--config", kConfig, "--bind", "127.0.0.1", "--port", "0", "--port-file", port_file.string(), "--script",
           script.string(), "--runs-dir", p.path("runs").string()});
  ASSERT_GT(p.waitPort(port_file), 0);
  // Wait for the progress bar (a few evaluations), then Ctrl-C.
  const auto deadline = Clock::now() + 20s;
  while (Clock::now() < deadline && p.out().find("evals  best cost") == std::string::npos)
    std::this_thread::sleep_for(50ms);

  ASSERT_NE(p.out().find("evals  best cost"), std::string::npos) << p.out() << p.err();
  p.signal(SIGINT);
  EXPECT_EQ(p.wait(30000ms), 0) << p.out() << p.err();
  const std::string out = p.out();
  EXPECT_HAS(out, "tune: cancelled after ");
  EXPECT_HAS(out, "fuzzy-PID (tuned)");   // the comparison with the best so far
  EXPECT_HAS(out, "after the tune");      // the server went on
  EXPECT_HAS(out, "tuned");               // gains show has the tuned column
  EXPECT_HAS(out, "(cancelled)");         // tune list: the session is in the catalog
  EXPECT_TRUE(fs::exists(p.path("runs") / "tuning"));
}

TEST(Program, AttachedOperatorObservesAndIsRefusedMotionWhileTheConsoleControls) {
  Program p("attach");
  const auto script = p.file("s.txt",
                             "expect robots >= 1 within 15\n"
                             "drive 0.2 0\n"
                             "wait 3\n"
                             "stop\n");
  const auto port_file = p.path("port");
  const auto sock = p.path("op.sock");
  p.start({"--config", kConfig, "--bind", "127.0.0.1", "--port", "0", "--port-file", port_file.string(),
           "--operator-socket", sock.string(), "--script", script.string()});
  const uint16_t port = p.waitPort(port_file);
  ASSERT_GT(port, 0);
  ScriptedRobot r;
  ASSERT_TRUE(r.connect(port));
  ASSERT_TRUE(r.hello("robot1"));
  r.startPump(50);
  // Once the console drives, a second operator attaches through the real binary.
  const auto driving = [&] {
    for (const auto& m : r.received())
      if (m.env.has_command() && m.env.command().has_teleop() && m.env.command().teleop().v_m_s() == 0.2) return true;
    return false;
  };
  // A bound on the wait, not a judgement of speed: under the unit phase's full load (ctest -j
  // 3 x cores) the server, the robot's Hello and the script's first drive took over 5 s once.
  const auto deadline = Clock::now() + 15s;
  while (!driving() && Clock::now() < deadline) std::this_thread::sleep_for(20ms);
  ASSERT_TRUE(driving()) << p.out() << p.err();
  const auto input = p.file("attach_in.txt", "control\ndrive 0.1 0\n" + std::string(5000, 'x') + "\nstatus\nstop\nquit\n");
  const std::string cmd =
      "timeout 10 " + kBinary + " --attach " + sock.string() + " < " + input.string() + " 2>&1";
  std::string attached;
  if (FILE* f = ::popen(cmd.c_str(), "r")) {
    char buf[4096];
    std::size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) attached.append(buf, n);
    EXPECT_EQ(::pclose(f), 0) << attached;
  }
  EXPECT_HAS(attached, "pc_server operator session: ");
  EXPECT_HAS(attached, "@console (session 1)");  // control shows who drives (the user running pc_server)
  EXPECT_HAS(attached, "robot1: drive refused: robot1 is controlled by ");
  EXPECT_HAS(attached, "robot1 |");  // the observer sees the status line
  EXPECT_HAS(attached, "robot1: stop accepted");  // and may stop it
  EXPECT_HAS(attached, "error: line longer than 4096 characters ignored");  // and the lines after it still run
  for (const auto& m : r.received())
    EXPECT_FALSE(m.env.has_command() && m.env.command().has_teleop() && m.env.command().teleop().v_m_s() == 0.1);
  EXPECT_EQ(p.wait(), 0) << p.out() << p.err();
  r.stopPump();
}
