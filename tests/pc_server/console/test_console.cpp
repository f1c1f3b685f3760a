// Console parsing and dispatch on strings, with a fake command sink that
// answers like a robot through the registry.
#include <gtest/gtest.h>

#include <numbers>

#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <thread>
#include <cmath>
#include <limits>

#include "pc_server/console/console.hpp"
#include "pc_server/terminal/line_reader.hpp"
#include "pc_server/operator/route_file.hpp"
#include "pc_server/console/status_line.hpp"
#include "shared/util/clock.hpp"
#include "tests/pc_server/console/manual_clock.hpp"
#include "tests/support/paths.hpp"

using namespace inspect;
using namespace inspect::server;
using inspect::test::ManualClock;

namespace {

constexpr uint64_t kSerial = 1;

/// Records commands; acks them through the registry as a robot would (or not).
class FakeSink : public CommandSink {
 public:
  FakeSink(RobotRegistry& r, ConsoleClock& clock) : registry_(r), clock_(clock) {}
  uint64_t setTeleop(const std::string& robot, double v, double w, double) override {
    if (!connected(robot)) return 0;
    teleop_active = true;
    last_v = v;
    last_w = w;
    v1::Command c;
    c.mutable_teleop();
    return answer(robot, c);
  }
  void clearTeleop(const std::string&) override { teleop_active = false; }
  void consoleAlive() override { ++alive_calls; }
  uint64_t sendCommand(const std::string& robot, v1::Command cmd) override {
    if (!connected(robot)) return 0;
    if (cmd.has_stop() || cmd.has_estop()) teleop_active = false;
    sent.push_back(cmd);
    return answer(robot, cmd);
  }

  std::optional<v1::Ack::Status> reply = v1::Ack::ACCEPTED;  // nullopt = never ack
  std::string reason;
  bool teleop_active = false;
  int alive_calls = 0;
  double last_v = 0, last_w = 0;
  std::vector<v1::Command> sent;

 private:
  uint64_t answer(const std::string& robot, const v1::Command&) {
    const uint64_t id = ++next_id_;
    if (reply) {
      v1::Ack a;
      a.set_command_id(id);
      a.set_status(*reply);
      a.set_reason(reason);
      registry_.onAck(robot, kSerial, a);
    }
    return id;
  }
  bool connected(const std::string& robot) {
    const auto snap = registry_.snapshot(robot, clock_.nowNs());
    return snap && snap->connected;
  }
  RobotRegistry& registry_;
  ConsoleClock& clock_;
  uint64_t next_id_ = 0;
};

class ConsoleTest : public ::testing::Test {
 protected:
  // The console's default options (1 s Ack timeout, 20 ms polls) on a clock
  // that moves only while it waits: exact timings, no real time.
  ConsoleTest() : clock_(stop_), sink_(registry_, clock_), console_(registry_, sink_, out_, stop_) {
    console_.setClock(clock_);
  }

  /// A robot as the link would register it; `settle` lets the console auto-select it now.
  void connectRobot(const std::string& id = "robot1", bool settle = true) {
    v1::Hello h;
    h.set_robot_id(id);
    registry_.onConnected(id, "127.0.0.1:1", kSerial, h, now());
    if (settle) (void)console_.background();
  }
  void telemetry(double x, v1::Mode mode = v1::IDLE, const std::string& id = "robot1") {
    v1::Telemetry t;
    t.mutable_pose()->set_x_m(x);
    t.set_mode(mode);
    t.set_faults(v1::FAULT_SENSOR_STALE);
    registry_.onTelemetry(id, kSerial, t, now());
  }
  /// Runs a line and returns (ok, output).
  std::pair<bool, std::string> run(const std::string& line, int line_no = 7) {
    out_.str("");
    const bool ok = console_.execute(line, line_no);
    return {ok, out_.str()};
  }

  int64_t now() { return clock_.nowNs(); }

  StopFlag stop_;
  ManualClock clock_;  // the console's: it moves only while the console waits
  RobotRegistry registry_;
  FakeSink sink_;
  std::ostringstream out_;
  Console console_;
};

#define EXPECT_HAS(text, part) EXPECT_NE((text).find(part), std::string::npos) << (text)

}  // namespace

TEST_F(ConsoleTest, BlankAndCommentLinesDoNothing) {
  EXPECT_TRUE(run("").first);
  EXPECT_TRUE(run("   # just a comment").first);
  EXPECT_EQ(console_.tally().commands, 0);
}

TEST_F(ConsoleTest, UnknownCommandIsAClearError) {
  const auto [ok, out] = run("drvie 0.1 0");
  EXPECT_FALSE(ok);
  EXPECT_EQ(out, "unknown command 'drvie' (try 'help')\n");
  EXPECT_EQ(console_.tally().errors, 1);
}

TEST_F(ConsoleTest, HelpListsEveryCommandAndExplainsOne) {
  auto [ok, out] = run("help");
  EXPECT_TRUE(ok);
  for (const char* c : {"robots", "select", "status", "drive", "teleop", "stop", "estop", "resume", "wait", "expect",
                        "echo", "quit"})
    EXPECT_HAS(out, c);
  std::tie(ok, out) = run("help drive");
  EXPECT_TRUE(ok);
  EXPECT_HAS(out, "drive <v_m_s> <w_rad_s>");
  std::tie(ok, out) = run("help nope");
  EXPECT_FALSE(ok);
  EXPECT_HAS(out, "unknown command 'nope'");
}

TEST_F(ConsoleTest, TheCommandTableParsesUnambiguously) { EXPECT_EQ(console_.tableProblems(), ""); }

TEST_F(ConsoleTest, CompletionComesFromTheCommandTable) {
  connectRobot();
  using V = std::vector<std::string>;
  EXPECT_EQ(console_.completions("tr"), (V{"track", "try"}));
  EXPECT_EQ(console_.completions("try tr"), (V{"track"}));
  EXPECT_EQ(console_.completions("dr"), (V{"drive"}));
  EXPECT_EQ(console_.completions("video "), (V{"bitrate", "fps", "keyframe", "off", "on", "res", "stats", "wide"}));
  EXPECT_EQ(console_.completions("gains push r"), (V{"robot1"}));
  EXPECT_EQ(console_.completions("help dri"), (V{"drive"}));
  EXPECT_EQ(console_.completions("control take f"), (V{"force"}));
  EXPECT_EQ(console_.completions("tune evals=30 s"), (V{"seed=", "seeds=", "speed=", "start="}));
  EXPECT_EQ(console_.completions("tune start=p"), (V{"start=paper"}));
  EXPECT_TRUE(console_.completions("drive 0.1 ").empty());
  EXPECT_TRUE(console_.completions("nonsense ").empty());
  // Help shows the same syntax the errors quote.
  EXPECT_EQ(console_.helpText("control").rfind("control\ncontrol take [force]\ncontrol release\n", 0), 0u);
  const auto [ok, out] = run("control take forse");
  EXPECT_FALSE(ok);
  EXPECT_HAS(out, "syntax: control | control take [force] | control release");
}

struct BadArgsCase {
  const char* line;
  const char* message;
};

inline void PrintTo(const BadArgsCase& c, std::ostream* os) { *os << '"' << c.line << '"'; }

class ConsoleBadArgs : public ConsoleTest, public ::testing::WithParamInterface<BadArgsCase> {};

TEST_P(ConsoleBadArgs, PrintsAClearMessage) {
  connectRobot();
  const auto [ok, out] = run(GetParam().line);
  EXPECT_FALSE(ok);
  EXPECT_HAS(out, GetParam().message);
}

INSTANTIATE_TEST_SUITE_P(
    Table, ConsoleBadArgs,
    ::testing::Values(BadArgsCase{"drive abc 0", "drive: 'abc' is not a number"},
                      BadArgsCase{"drive 0.1 nan", "drive: 'nan' is not a number"},
                      BadArgsCase{"drive 0.1", "drive: needs two numbers"},
                      BadArgsCase{"drive 0.1 0 3", "drive: needs two numbers"},
                      BadArgsCase{"drive 5 0", "drive: v 5 m/s is outside [-1, 1]"},
                      BadArgsCase{"drive 0 -2.5", "drive: w -2.5 rad/s is outside [-2, 2]"},
                      BadArgsCase{"wait", "wait: needs one number"}, BadArgsCase{"wait soon", "'soon' is not a number"},
                      BadArgsCase{"wait -1", "outside [0, 3600]"}, BadArgsCase{"select a b", "needs one robot id"},
                      BadArgsCase{"select bad!id", "not a valid robot id"},
                      BadArgsCase{"stop now", "stop: takes no arguments"},
                      BadArgsCase{"teleop fast", "teleop: unknown mode 'fast'"},
                      BadArgsCase{"teleop", "keyboard teleop needs an interactive terminal"},
                      BadArgsCase{"status a b", "status: takes at most one"}));

TEST_F(ConsoleTest, CommandsNeedASelectedConnectedRobot) {
  auto [ok, out] = run("drive 0.1 0");
  EXPECT_FALSE(ok);
  EXPECT_EQ(out, "drive: no robot selected\n");
  std::tie(ok, out) = run("select robot2");
  EXPECT_TRUE(ok);
  EXPECT_EQ(out, "selected robot2 (not connected yet)\n");
  std::tie(ok, out) = run("estop");
  EXPECT_FALSE(ok);
  EXPECT_EQ(out, "estop: robot2 is not connected\n");
}

TEST_F(ConsoleTest, FirstRobotToConnectIsSelected) {
  connectRobot("robot9", false);
  connectRobot("robot3", false);
  const auto [ok, out] = run("status");
  EXPECT_TRUE(ok);
  EXPECT_HAS(out, "selected robot9 (the first robot to connect)");
  EXPECT_EQ(console_.selected(), "robot9");
}

TEST_F(ConsoleTest, DriveSetsTheSetPointAndReportsTheAck) {
  connectRobot();
  auto [ok, out] = run("drive 0.3 -0.5");
  EXPECT_TRUE(ok) << out;
  EXPECT_HAS(out, "robot1: drive +0.30 m/s -0.50 rad/s accepted");
  EXPECT_TRUE(sink_.teleop_active);
  EXPECT_DOUBLE_EQ(sink_.last_v, 0.3);
  EXPECT_DOUBLE_EQ(sink_.last_w, -0.5);
  std::tie(ok, out) = run("stop");
  EXPECT_TRUE(ok);
  EXPECT_HAS(out, "robot1: stop accepted");
  EXPECT_FALSE(sink_.teleop_active);
  ASSERT_EQ(sink_.sent.size(), 1u);
  EXPECT_TRUE(sink_.sent[0].has_stop());
}

TEST_F(ConsoleTest, RejectedDriveClearsTheSetPoint) {
  connectRobot();
  sink_.reply = v1::Ack::REJECTED;
  sink_.reason = "robot in ESTOP";
  const auto [ok, out] = run("drive 0.3 0");
  EXPECT_FALSE(ok);
  EXPECT_HAS(out, "rejected: robot in ESTOP");
  EXPECT_FALSE(sink_.teleop_active);
}

TEST_F(ConsoleTest, EstopResumeAckMessages) {
  connectRobot();
  auto [ok, out] = run("estop");
  EXPECT_TRUE(ok);
  EXPECT_EQ(out, "robot1: estop accepted\n");
  EXPECT_TRUE(sink_.sent.back().has_estop());
  sink_.reply = v1::Ack::REJECTED;
  sink_.reason = "fault still active";
  std::tie(ok, out) = run("resume");
  EXPECT_FALSE(ok);
  EXPECT_EQ(out, "robot1: resume rejected: fault still active\n");
  sink_.reply = std::nullopt;
  const double t0 = clock_.elapsedS();
  std::tie(ok, out) = run("stop");
  EXPECT_FALSE(ok);
  EXPECT_EQ(out, "robot1: stop: no ack within 1 s\n");
  // It waited the Ack timeout, no more, no less, asleep on the registry's Ack
  // signal (waking every 50 ms only to print the status line and events).
  EXPECT_NEAR(clock_.elapsedS() - t0, 1.0, 1e-6);
  EXPECT_EQ(clock_.sleeps(), 20);
}

TEST_F(ConsoleTest, AnAckWakesTheConsoleWhenItArrives) {
  connectRobot();
  sink_.reply = std::nullopt;  // the Ack comes later, from the "link"
  clock_.at(0.3, [this] {
    v1::Ack a;
    a.set_command_id(1);  // the first command the sink sends
    a.set_status(v1::Ack::ACCEPTED);
    registry_.onAck("robot1", kSerial, a);
  });
  const double t0 = clock_.elapsedS();
  const auto [ok, out] = run("stop");
  EXPECT_TRUE(ok) << out;
  EXPECT_NEAR(clock_.elapsedS() - t0, 0.3, 1e-6) << "woken by the Ack, not at the next poll";
  EXPECT_EQ(clock_.sleeps(), 6);  // five 50 ms waits, then the one the Ack ended
}

TEST(WakeSignal, AStopRequestEndsTheWait) {
  // Without the stop's wake-up this wait would last an hour (the test's timeout fails it first).
  StopFlag stop;
  WakeSignal s;
  std::thread t([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    stop.request();
  });
  EXPECT_FALSE(stop.waitChange(s, s.generation(), std::chrono::hours(1)));
  t.join();
  EXPECT_FALSE(stop.waitChange(s, s.generation(), std::chrono::hours(1)));  // already stopped: at once
}

TEST(WakeSignal, NoLostWakeUp) {
  WakeSignal s;
  const uint64_t seen = s.generation();
  s.notify();  // between the look and the wait
  EXPECT_TRUE(s.waitChange(seen, std::chrono::hours(1)));  // returns at once
  EXPECT_FALSE(s.waitChange(s.generation(), std::chrono::milliseconds(1)));
}

TEST_F(ConsoleTest, RobotsTableAndStatusLine) {
  connectRobot();
  telemetry(1.2, v1::TELEOP);
  auto [ok, out] = run("robots");
  EXPECT_TRUE(ok);
  EXPECT_HAS(out, "* robot1");
  EXPECT_HAS(out, "127.0.0.1:1");
  EXPECT_HAS(out, "TELEOP");
  std::tie(ok, out) = run("status");
  EXPECT_TRUE(ok);
  // The test's telemetry carries no measured speeds: unknown, not 0 (link protocol 2).
  EXPECT_HAS(out, "robot1 | TELEOP | v unknown w unknown | x 1.20 y 0.00 th +0.00");
  EXPECT_HAS(out, "faults SENSOR_STALE");
  std::tie(ok, out) = run("status ghost");
  EXPECT_EQ(out, "ghost | not connected yet\n");
}

TEST_F(ConsoleTest, EchoPrintsTheRestOfTheLine) {
  const auto [ok, out] = run("echo  hello   world  # note");
  EXPECT_TRUE(ok);
  EXPECT_EQ(out, "hello   world\n");
}

TEST_F(ConsoleTest, WaitSleepsAndQuitIsRecorded) {
  EXPECT_TRUE(run("wait 0.05").first);
  EXPECT_NEAR(clock_.elapsedS(), 0.05, 1e-6);
  EXPECT_TRUE(run("wait 10").first);  // on the console's clock: no real time
  EXPECT_NEAR(clock_.elapsedS(), 10.05, 1e-6);
  EXPECT_FALSE(console_.quitRequested());
  EXPECT_TRUE(run("exit").first);
  EXPECT_TRUE(console_.quitRequested());
}

TEST_F(ConsoleTest, ConsoleReportsItIsAliveWhileWaiting) {
  // Polls every 20 ms: a sign of life as the line starts, before each of the 25 sleeps and at the end.
  EXPECT_TRUE(run("wait 0.5").first);
  EXPECT_EQ(clock_.sleeps(), 25);
  EXPECT_EQ(sink_.alive_calls, 27) << "the console watchdog needs a sign of life every poll";
}

TEST_F(ConsoleTest, WaitIsInterruptedByStop) {
  clock_.at(0.25, [this] { stop_.request(); });
  const auto [ok, out] = run("wait 10");
  EXPECT_FALSE(ok);
  EXPECT_EQ(out, "wait: interrupted (server stopping)\n");
  EXPECT_NEAR(clock_.elapsedS(), 0.25, 1e-6) << "the wait ends with the stop, not at 10 s";
}

TEST_F(ConsoleTest, EventsArePrintedAsTheyCome) {
  connectRobot();
  v1::Event e;
  e.set_kind(v1::Event::FAULT_RAISED);
  e.set_text("link lost");
  registry_.onEvent("robot1", kSerial, e);
  const auto [ok, out] = run("echo x");
  EXPECT_HAS(out, "[robot1] FAULT_RAISED: link lost\n");
}

// --- expect ---

TEST_F(ConsoleTest, ExpectPassesAndFailsWithTheWantedText) {
  connectRobot();
  telemetry(1.93);
  auto [ok, out] = run("expect x ~ 2.0 0.05 ", 12);
  EXPECT_FALSE(ok);
  EXPECT_EQ(out, "EXPECT FAILED (line 12): x = 1.93, wanted ~ 2.0 +- 0.05\n");
  std::tie(ok, out) = run("expect x ~ 2.0 +- 0.1", 13);
  EXPECT_TRUE(ok);
  EXPECT_EQ(out, "expect ok (line 13): x = 1.93\n");
  std::tie(ok, out) = run("expect mode == IDLE");
  EXPECT_TRUE(ok);
  EXPECT_HAS(out, "mode = IDLE");
  std::tie(ok, out) = run("expect faults == 0x2");
  EXPECT_TRUE(ok) << out;
  std::tie(ok, out) = run("expect connected == 1");
  EXPECT_TRUE(ok);
  std::tie(ok, out) = run("expect robots >= 2");
  EXPECT_FALSE(ok);
  EXPECT_HAS(out, "robots = 1, wanted >= 2");
  EXPECT_EQ(console_.tally().expects_passed, 4);
  EXPECT_EQ(console_.tally().expects_failed, 2);
}

TEST_F(ConsoleTest, ExpectUnknownFieldCountsAsFailure) {
  connectRobot();
  const auto [ok, out] = run("expect speed > 1", 3);
  EXPECT_FALSE(ok);
  EXPECT_HAS(out, "EXPECT FAILED (line 3): expect: unknown field 'speed'");
  EXPECT_EQ(console_.tally().expects_failed, 1);
}

TEST_F(ConsoleTest, ExpectWithoutTelemetrySaysSo) {
  auto [ok, out] = run("expect x > 0");
  EXPECT_FALSE(ok);
  EXPECT_HAS(out, "x: no robot selected");
  connectRobot();
  std::tie(ok, out) = run("expect x > 0");
  EXPECT_FALSE(ok);
  EXPECT_HAS(out, "x: no telemetry from robot1 yet");
  std::tie(ok, out) = run("expect telemetry_hz == 0");
  EXPECT_TRUE(ok) << out;
}

TEST_F(ConsoleTest, ExpectWithinPollsUntilTrue) {
  connectRobot();
  telemetry(0.0);
  clock_.at(0.1, [this] { telemetry(2.01); });
  const auto [ok, out] = run("expect x ~ 2 0.05 within 2");
  EXPECT_TRUE(ok) << out;
  EXPECT_HAS(out, "x = 2.01");
  // Held at the first poll after the telemetry came (20 ms polls), long before the 2 s ran out.
  EXPECT_NEAR(clock_.elapsedS(), 0.1, 1e-6);
}

TEST_F(ConsoleTest, ExpectWithinTimesOut) {
  connectRobot();
  telemetry(0.5);
  const auto [ok, out] = run("expect x >= 1 within 0.2", 4);
  EXPECT_FALSE(ok);
  EXPECT_EQ(out, "EXPECT FAILED (line 4): x = 0.5, wanted >= 1 within 0.2 s\n");
  EXPECT_NEAR(clock_.elapsedS(), 0.2, 1e-6) << "it gave up when the 0.2 s ran out";
}

TEST_F(ConsoleTest, ExpectRobotsWorksWithoutSelection) {
  auto [ok, out] = run("expect robots == 0");
  EXPECT_TRUE(ok) << out;
  connectRobot("r1");
  connectRobot("r2");
  std::tie(ok, out) = run("expect robots == 2");
  EXPECT_TRUE(ok) << out;
}

// --- navigation: goto, route, nav telemetry ---

namespace {

// A file in a fresh temporary directory, removed with the object.
struct TempFile {
  std::string path;
  explicit TempFile(const std::string& name, const std::string& text) {
    char dir[] = "/tmp/console_route_XXXXXX";
    path = std::string(::mkdtemp(dir)) + "/" + name;
    std::ofstream(path) << text;
  }
  ~TempFile() {
    std::remove(path.c_str());
    std::remove(path.substr(0, path.rfind('/')).c_str());
  }
};

void navTelemetry(RobotRegistry& registry, const std::string& nav_mode, int64_t now_ns) {
  v1::Telemetry t;
  t.set_mode(nav_mode.empty() ? v1::IDLE : v1::NAVIGATING);
  t.set_nav_mode(nav_mode);
  t.set_goal_distance_m(1.25);
  t.set_goal_index(1);
  t.set_goal_count(3);
  t.set_nav_switches(4);
  registry.onTelemetry("robot1", kSerial, t, now_ns);
}

}  // namespace

TEST_F(ConsoleTest, GotoSendsOneGoalAndReportsCompletion) {
  connectRobot();
  auto [ok, out] = run("goto 2 -1.5 0.3");
  EXPECT_TRUE(ok) << out;
  EXPECT_EQ(out, "robot1: goto accepted\n");
  ASSERT_EQ(sink_.sent.size(), 1u);
  const auto& g = sink_.sent[0].go_to();
  ASSERT_EQ(g.points_size(), 1);
  EXPECT_DOUBLE_EQ(g.points(0).x_m(), 2.0);
  EXPECT_DOUBLE_EQ(g.points(0).y_m(), -1.5);
  EXPECT_DOUBLE_EQ(g.speed_m_s(), 0.3);
  EXPECT_EQ(g.name(), "");
  // The robot's second Ack, COMPLETED with the same id, is printed once when it comes.
  v1::Ack done;
  done.set_command_id(1);
  done.set_status(v1::Ack::COMPLETED);
  registry_.onAck("robot1", kSerial, done);
  std::tie(ok, out) = run("echo x");
  EXPECT_EQ(out, "robot1: goto completed\nx\n");
  std::tie(ok, out) = run("echo y");
  EXPECT_EQ(out, "y\n");
  // Without a speed the robot's default is asked for (0).
  std::tie(ok, out) = run("goto 1 1");
  EXPECT_TRUE(ok) << out;
  EXPECT_DOUBLE_EQ(sink_.sent.back().go_to().speed_m_s(), 0.0);
}

TEST_F(ConsoleTest, GotoSyntaxErrorsNameTheProblem) {
  connectRobot();
  struct Case {
    const char* line;
    const char* message;
  };
  for (const Case& c : {Case{"goto 1", "goto: syntax: goto <x_m> <y_m> [speed_m_s] [force]\n"},
                        Case{"goto 1 2 3 4", "goto: syntax: goto <x_m> <y_m> [speed_m_s] [force]\n"},
                        Case{"goto a 1", "goto: 'a' is not a number\n"},
                        Case{"goto 1 nan", "goto: 'nan' is not a number\n"},
                        Case{"goto 1 1 2", "goto: speed 2 m/s is outside (0, 1]\n"},
                        Case{"goto 1 1 0", "goto: speed 0 m/s is outside (0, 1]\n"},
                        Case{"goto 5000 0", "goto: x and y must be in [-1000, 1000] m\n"}}) {
    const auto [ok, out] = run(c.line);
    EXPECT_FALSE(ok) << c.line;
    EXPECT_EQ(out, c.message) << c.line;
  }
  EXPECT_TRUE(sink_.sent.empty());
  sink_.reply = v1::Ack::REJECTED;
  sink_.reason = "e-stop latched: resume first";
  const auto [ok, out] = run("goto 1 1");
  EXPECT_FALSE(ok);
  EXPECT_EQ(out, "robot1: goto rejected: e-stop latched: resume first\n");
}

TEST_F(ConsoleTest, RouteFileIsSentAsOneGoTo) {
  connectRobot();
  const TempFile f("tour.yaml", "name: tour\nspeed_m_s: 0.4\nwaypoints_m: [1, 0,  1, 1.5,  0, 1.5]\n");
  auto [ok, out] = run("route " + f.path);
  EXPECT_TRUE(ok) << out;
  EXPECT_EQ(out, "route 'tour': 3 points at 0.4 m/s\nrobot1: route accepted\n");
  ASSERT_EQ(sink_.sent.size(), 1u);
  const auto& g = sink_.sent[0].go_to();
  EXPECT_EQ(g.name(), "tour");
  EXPECT_DOUBLE_EQ(g.speed_m_s(), 0.4);
  ASSERT_EQ(g.points_size(), 3);
  EXPECT_DOUBLE_EQ(g.points(1).x_m(), 1.0);
  EXPECT_DOUBLE_EQ(g.points(1).y_m(), 1.5);
  // Name and speed are optional: the file name, the robot's speed.
  const TempFile bare("loop.yaml", "waypoints_m: [2, 0]\n");
  std::tie(ok, out) = run("route " + bare.path);
  EXPECT_TRUE(ok) << out;
  EXPECT_EQ(sink_.sent.back().go_to().name(), "loop");
  EXPECT_DOUBLE_EQ(sink_.sent.back().go_to().speed_m_s(), 0.0);
}

TEST_F(ConsoleTest, ShippedExampleRouteLoads) {
  const Route r = loadRouteFile(inspect::test::srcPath("config/routes/warehouse_tour.yaml"));
  EXPECT_EQ(r.name, "warehouse_tour");
  EXPECT_GE(r.waypointsM().size(), 4u);
  EXPECT_EQ(r.waypointsM().size() % 2, 0u);
}

TEST_F(ConsoleTest, BadRouteFileIsOneLineNamingFileAndKey) {
  connectRobot();
  struct Case {
    const char* yaml;
    const char* key_and_reason;
  };
  std::string hundred_and_one = "waypoints_m: [";
  for (int i = 0; i < 101; ++i) hundred_and_one += std::string(i ? ", " : "") + "1, 1";
  hundred_and_one += "]\n";
  for (const Case& c : {Case{"waypoint_m: [1, 1]\n", "waypoints_m: required list"},
                        Case{"waypoints_m: [1, 1]\nspeed: 0.3\n", "speed: unknown key"},
                        Case{"waypoints_m: [1, 1, 2]\n", "waypoints_m: 3 numbers: needs pairs x, y"},
                        Case{"waypoints_m: []\n", "waypoints_m: needs at least one point"},
                        Case{"waypoints_m: [1, .nan]\n", "waypoints_m: element 1 must be finite"},
                        Case{"waypoints_m: [1, .inf]\n", "waypoints_m: element 1 must be finite"},
                        Case{"waypoints_m: [1, x]\n", "waypoints_m: element 1 is not a number"},
                        Case{"waypoints_m: [1, 1]\nspeed_m_s: 3\n", "speed_m_s:"},
                        Case{"waypoints_m: [1, 1]\nspeed_m_s: 0\n", "speed_m_s: must be > 0"},
                        Case{hundred_and_one.c_str(), "waypoints_m: 101 points: at most 100"}}) {
    const TempFile f("bad.yaml", c.yaml);
    const auto [ok, out] = run("route " + f.path);
    EXPECT_FALSE(ok) << c.yaml;
    EXPECT_EQ(out.rfind("route: " + f.path + ": " + c.key_and_reason, 0), 0u) << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  }
  auto [ok, out] = run("route /nonexistent/route.yaml");
  EXPECT_FALSE(ok);
  EXPECT_EQ(out, "route: /nonexistent/route.yaml: cannot open file\n");
  std::tie(ok, out) = run("route");
  EXPECT_EQ(out, "route: needs one route: route <file|name>\n");
  std::tie(ok, out) = run("route no_such_route");
  EXPECT_EQ(out, "route: no route 'no_such_route': neither a file nor config/routes/no_such_route.yaml\n");
  EXPECT_TRUE(sink_.sent.empty());
}

TEST_F(ConsoleTest, ExpectNavigationFieldsAndStatusLine) {
  connectRobot();
  navTelemetry(registry_, "FOLLOW_CW", now());
  auto [ok, out] = run("expect nav_mode == FOLLOW_CW");
  EXPECT_TRUE(ok) << out;
  EXPECT_HAS(out, "nav_mode = FOLLOW_CW");
  std::tie(ok, out) = run("expect nav_mode == follow_ccw", 5);
  EXPECT_FALSE(ok);
  EXPECT_EQ(out, "EXPECT FAILED (line 5): nav_mode = FOLLOW_CW, wanted == follow_ccw\n");
  std::tie(ok, out) = run("expect nav_mode == SIDEWAYS");
  EXPECT_FALSE(ok);
  EXPECT_HAS(out, "or a navigation mode (NONE, GO_TO_GOAL");
  EXPECT_TRUE(run("expect goal_dist ~ 1.25 0.01").first);
  EXPECT_TRUE(run("expect goal_index == 1").first);
  EXPECT_TRUE(run("expect goal_count == 3").first);
  EXPECT_TRUE(run("expect nav_switches >= 4").first);
  EXPECT_TRUE(run("expect mode == NAVIGATING").first);
  std::tie(ok, out) = run("status");
  EXPECT_HAS(out, "robot1 | NAVIGATING | ");
  EXPECT_HAS(out, " | nav FOLLOW_CW goal 2/3 1.25 m sw 4 | ");
  navTelemetry(registry_, "", now());
  std::tie(ok, out) = run("expect nav_mode == NONE");
  EXPECT_TRUE(ok) << out;
  std::tie(ok, out) = run("status");
  EXPECT_EQ(out.find(" nav "), std::string::npos) << out;
}

INSTANTIATE_TEST_SUITE_P(
    Video, ConsoleBadArgs,
    ::testing::Values(BadArgsCase{"video", "syntax: video on|off"}, BadArgsCase{"video loud", "unknown 'loud'"},
                      BadArgsCase{"video res 7x5", "video: res '7x5': want <W>x<H>, even, 64 to 4096"},
                      BadArgsCase{"video res 640", "video: res '640'"},
                      BadArgsCase{"video res 641x480", "video: res '641x480'"},
                      BadArgsCase{"video fps 0", "video: fps '0': want 1 to 120"},
                      BadArgsCase{"video fps many", "video: fps 'many'"},
                      BadArgsCase{"video bitrate 10", "video: bitrate '10': want 50 to 50000 kbit/s"},
                      BadArgsCase{"video on now", "syntax: video"},
                      BadArgsCase{"video wide stats", "video: unknown what 'stats' (on, off or keyframe)"},
                      BadArgsCase{"video wide bitrate 5", "bitrate"},
                      BadArgsCase{"ptz 200 0", "ptz: pan must be within [-180, 180] and tilt within [-90, 90]"},
                      BadArgsCase{"ptz 10", "syntax: ptz <pan_deg> <tilt_deg> | ptz home"},
                      BadArgsCase{"ptz left up", "syntax: ptz"},
                      BadArgsCase{"snapshot a.png b.png", "syntax: snapshot wide [file.png] | snapshot [file.png]"},
                      BadArgsCase{"snapshot", "snapshot: the server runs without video"}));

TEST_F(ConsoleTest, VideoAndPtzCommandsReachTheRobot) {
  connectRobot();
  auto [ok, out] = run("video res 1280x720");
  EXPECT_TRUE(ok) << out;
  EXPECT_HAS(out, "robot1: video res accepted");
  ASSERT_EQ(sink_.sent.size(), 1u);
  EXPECT_EQ(sink_.sent[0].video().width(), 1280u);
  EXPECT_EQ(sink_.sent[0].video().height(), 720u);
  EXPECT_FALSE(sink_.sent[0].video().has_enabled());
  std::tie(ok, out) = run("video off");
  EXPECT_TRUE(ok) << out;
  ASSERT_TRUE(sink_.sent.back().video().has_enabled());
  EXPECT_FALSE(sink_.sent.back().video().enabled());
  std::tie(ok, out) = run("video keyframe");
  EXPECT_TRUE(sink_.sent.back().video().keyframe());
  std::tie(ok, out) = run("video bitrate 800");
  EXPECT_EQ(sink_.sent.back().video().bitrate_kbps(), 800u);
  std::tie(ok, out) = run("video fps 15");
  EXPECT_DOUBLE_EQ(sink_.sent.back().video().fps(), 15.0);
  std::tie(ok, out) = run("ptz 90 -45");
  EXPECT_TRUE(ok) << out;
  EXPECT_NEAR(sink_.sent.back().ptz().pan_rad(), std::numbers::pi / 2, 1e-12);
  EXPECT_NEAR(sink_.sent.back().ptz().tilt_rad(), -std::numbers::pi / 4, 1e-12);
  std::tie(ok, out) = run("ptz home");
  EXPECT_TRUE(sink_.sent.back().ptz().home());
  EXPECT_EQ(sink_.sent[0].video().head(), v1::PTZ_HEAD);
  // The wide head's stream (docs/video.md "The wide head's stream"): refused
  // here while the robot's telemetry shows none (an older robot would take it
  // for the PTZ head's).
  v1::Telemetry t;
  t.mutable_video()->set_ssrc(42);
  registry_.onTelemetry("robot1", kSerial, t, now());
  const auto sent = sink_.sent.size();
  std::tie(ok, out) = run("video wide bitrate 500");
  EXPECT_FALSE(ok);
  EXPECT_HAS(out, "robot1 does not stream a wide head");
  EXPECT_EQ(sink_.sent.size(), sent) << "nothing sent";
  t.mutable_wide_video()->set_ssrc(43);
  registry_.onTelemetry("robot1", kSerial, t, now());
  std::tie(ok, out) = run("video wide bitrate 500");
  EXPECT_TRUE(ok) << out;
  EXPECT_HAS(out, "robot1: video wide bitrate accepted");
  EXPECT_EQ(sink_.sent.back().video().head(), v1::WIDE_HEAD);
  EXPECT_EQ(sink_.sent.back().video().bitrate_kbps(), 500u);
  std::tie(ok, out) = run("video wide off");
  EXPECT_EQ(sink_.sent.back().video().head(), v1::WIDE_HEAD);
  ASSERT_TRUE(sink_.sent.back().video().has_enabled());
  EXPECT_FALSE(sink_.sent.back().video().enabled());
  std::tie(ok, out) = run("video wide keyframe");
  EXPECT_TRUE(sink_.sent.back().video().keyframe());
  EXPECT_EQ(sink_.sent.back().video().head(), v1::WIDE_HEAD);
  sink_.reply = v1::Ack::REJECTED;
  sink_.reason = "video: this robot does not stream a wide head (wide_head.stream)";
  std::tie(ok, out) = run("video wide on");
  EXPECT_FALSE(ok);
  EXPECT_HAS(out, "robot1: video wide on rejected: video: this robot does not stream a wide head");
  sink_.reason = "video: this robot has no video stream (see its log)";
  std::tie(ok, out) = run("video on");
  EXPECT_FALSE(ok);
  EXPECT_HAS(out, "robot1: video on rejected: video: this robot has no video stream");
}

TEST_F(ConsoleTest, VideoStatsWithoutAServerStreamSaysSo) {
  connectRobot();
  v1::Telemetry t;
  t.mutable_video()->set_enabled(true);
  t.mutable_video()->set_ssrc(42);
  t.mutable_video()->set_frames_encoded(300);
  registry_.onTelemetry("robot1", kSerial, t, now());
  const auto [ok, out] = run("video stats");
  EXPECT_TRUE(ok) << out;
  EXPECT_HAS(out, "SSRC 42");
  EXPECT_HAS(out, "encoded 300");
  EXPECT_HAS(out, "server: video off");
}

TEST_F(ConsoleTest, VideoStatsAndTheStatusLineShowTheRateInForceAndWhy) {
  connectRobot();
  v1::Telemetry t;
  auto* v = t.mutable_video();
  v->set_enabled(true);
  v->set_adapt(true);
  v->set_min_kbps(300);
  v->set_max_kbps(2000);
  v->set_rate_kbps(300);
  v->set_send_width(640);
  v->set_send_height(480);
  v->set_send_fps(15);
  v->set_rate_level(1);
  v->set_rate_reason("loss 21.1 % > 10 %: x0.89; below 300 kbit/s: frame rate halved");
  v->set_rate_age_s(1.5);
  v->set_rate_changes(17);
  v->set_peer_loss_pct(21.1);
  v->set_rtt_ms(20.4);
  registry_.onTelemetry("robot1", kSerial, t, now());
  const auto [ok, out] = run("video stats");
  EXPECT_TRUE(ok) << out;
  EXPECT_HAS(out, "robot rate: 300 kbit/s, 640x480 @ 15 fps (adapting in 300-2000 kbit/s, level 1); last change 1.5 s ago: "
                  "loss 21.1 % > 10 %: x0.89; below 300 kbit/s: frame rate halved (17 changes)");
  EXPECT_HAS(out, "robot feedback: receiver's loss 21.1 %, RTT 20.4 ms, NACKed 0, retransmitted 0, repeat NACKs 0, "
                  "not in history 0");
  const std::string line = server::statusLine("robot1", registry_.snapshot("robot1", now()), nullptr);
  EXPECT_HAS(line, "| rate 300 kbit/s 640x480@15 (loss 21.1 % > 10 %: x0.89; below 300 kbit/s: frame rate halved)");
}

TEST_F(ConsoleTest, RecordingCommandsWithoutARecorderSaySo) {
  connectRobot();
  for (const char* line : {"record start x", "runs", "run show 1"}) {
    const auto [ok, out] = run(line);
    EXPECT_FALSE(ok) << line;
    EXPECT_HAS(out, "the server records nothing");
  }
}

// ---- Gas: inspect, alarms, ack, the status line ----

TEST_F(ConsoleTest, InspectSendsAnInspectionGoToWithDwellPresetsAndLabels) {
  connectRobot();
  const TempFile f("lab.yaml",
                   "name: lab\nspeed_m_s: 0.3\npoints:\n"
                   "  - {at: [1, 0]}\n"
                   "  - {at: [2, 0.5], dwell_s: 4, ptz: {pan_deg: 90, tilt_deg: -10}, label: valve}\n"
                   "  - {at: [0, 0], ptz: {home: true}}\n");
  auto [ok, out] = run("inspect " + f.path);
  EXPECT_TRUE(ok) << out;
  EXPECT_EQ(out,
            "inspect: note: the server records nothing (--no-record): no run, no report\n"
            "inspection 'lab': 3 points, 1 inspection points at 0.3 m/s\nrobot1: inspect accepted\n");
  ASSERT_EQ(sink_.sent.size(), 1u);
  const auto& g = sink_.sent[0].go_to();
  EXPECT_TRUE(g.inspection());
  ASSERT_EQ(g.points_size(), 3);
  EXPECT_DOUBLE_EQ(g.points(1).dwell_s(), 4.0);
  EXPECT_EQ(g.points(1).label(), "valve");
  EXPECT_NEAR(g.points(1).ptz().pan_rad(), M_PI / 2, 1e-12);
  EXPECT_NEAR(g.points(1).ptz().tilt_rad(), -10 * M_PI / 180, 1e-12);
  EXPECT_TRUE(g.points(2).ptz().home());
  EXPECT_FALSE(g.points(0).has_ptz());
  // A speed on the command line wins over the file's.
  std::tie(ok, out) = run("inspect " + f.path + " 0.5");
  EXPECT_TRUE(ok) << out;
  EXPECT_DOUBLE_EQ(sink_.sent.back().go_to().speed_m_s(), 0.5);
  std::tie(ok, out) = run("inspect " + f.path + " 3");
  EXPECT_FALSE(ok);
  EXPECT_EQ(out, "inspect: speed_m_s '3' must be a number in (0, 1] m/s\n");
}

TEST_F(ConsoleTest, ShippedInspectionRouteLoadsWithItsMap) {
  const Route r = loadRouteFile(inspect::test::srcPath("config/routes/gas_lab_inspection.yaml"));
  EXPECT_EQ(r.name, "gas_lab_inspection");
  EXPECT_EQ(r.points.size(), 7u);
  EXPECT_EQ(r.inspectionPoints(), 2);
  EXPECT_NE(r.map.find("gas_lab.yaml"), std::string::npos) << r.map;
}

TEST_F(ConsoleTest, BadInspectionRoutesNameTheKey) {
  connectRobot();
  struct Case {
    const char* yaml;
    const char* key_and_reason;
  };
  for (const Case& c :
       {Case{"points: [{at: [1, 1], dwell_s: -1}]\n", "points[0].dwell_s"},
        Case{"points: [{at: [1]}]\n", "points[0].at"},
        Case{"points: [{at: [1, 1], ptz: {pan_deg: 400}}]\n", "points[0].ptz.pan_deg"},
        Case{"points: [{at: [1, 1], colour: red}]\n", "points[0].colour: unknown key"},
        Case{"points: [{at: [1, 1]}]\nwaypoints_m: [1, 1]\n", "points: give either waypoints_m or points"},
        Case{"points: [{at: [1, 1]}]\nmap: /nonexistent/world.yaml\n", "map: '/nonexistent/world.yaml' does not exist"}}) {
    const TempFile f("bad.yaml", c.yaml);
    const auto [ok, out] = run("inspect " + f.path);
    EXPECT_FALSE(ok) << c.yaml;
    EXPECT_EQ(out.rfind("inspect: " + f.path + ": " + c.key_and_reason, 0), 0u) << out;
  }
  const auto [ok, out] = run("inspect no_such_route");
  EXPECT_FALSE(ok);
  EXPECT_EQ(out, "inspect: no route 'no_such_route': neither a file nor config/routes/no_such_route.yaml\n");
  EXPECT_TRUE(sink_.sent.empty());
}

TEST_F(ConsoleTest, AlarmsAreListedAndAcknowledged) {
  connectRobot();
  auto [ok, out] = run("alarms");
  EXPECT_TRUE(ok);
  EXPECT_EQ(out, "no active or unacknowledged gas alarms\n");
  v1::Event e;
  e.set_kind(v1::Event::ALARM_RAISED);
  e.set_text("gas H2S HIGH alarm raised: 12.30 ppm (threshold 10.00) at (2.35, 3.02)");
  auto* a = e.mutable_gas_alarm();
  a->set_id(4);
  a->set_channel_name("H2S");
  a->set_level(v1::GasAlarm::HIGH);
  a->set_active(true);
  a->set_value(12.3);
  a->set_threshold(10.0);
  a->set_peak(12.3);
  a->set_unit("ppm");
  a->mutable_pose()->set_x_m(2.35);
  a->mutable_pose()->set_y_m(3.02);
  registry_.onEvent("robot1", kSerial, e, now());
  // Printed at once (plain text here; red with a bell on a terminal).
  EXPECT_EQ(console_.background(),
            "[robot1] ALARM_RAISED: gas H2S HIGH alarm raised: 12.30 ppm (threshold 10.00) at (2.35, 3.02)\n");
  std::tie(ok, out) = run("alarms");
  EXPECT_TRUE(ok);
  EXPECT_EQ(out.rfind("#1 robot1 H2S HIGH 12.3 ppm (A2 10 ppm, worst 12.3 ppm) at (2.35, 3.02): raised ", 0), 0u)
      << out;
  EXPECT_NE(out.find("ACTIVE, unacknowledged"), std::string::npos) << out;
  std::tie(ok, out) = run("ack 9");
  EXPECT_FALSE(ok);
  EXPECT_EQ(out, "ack: no alarm #9 (alarms lists them)\n");
  std::tie(ok, out) = run("ack x");
  EXPECT_FALSE(ok);
  EXPECT_EQ(out, "ack: 'x' is not an alarm number (alarms lists them)\n");
  std::tie(ok, out) = run("ack 1");
  EXPECT_TRUE(ok);
  EXPECT_EQ(out, "robot1: alarm #1 (H2S HIGH) acknowledged by the operator\n");
  std::tie(ok, out) = run("alarms");
  EXPECT_NE(out.find("ACTIVE, acknowledged"), std::string::npos) << "active alarms stay listed: " << out;
  std::tie(ok, out) = run("ack all");
  EXPECT_EQ(out, "ack: nothing to acknowledge\n");
  std::tie(ok, out) = run("alarms everything");
  EXPECT_FALSE(ok);
  EXPECT_EQ(out, "alarms: syntax: alarms [all]\n");
}

TEST_F(ConsoleTest, StatusLineNamesGasChannelsAndShowsAlarms) {
  v1::Hello h;
  h.set_robot_id("robot1");
  for (const char* n : {"CH4", "H2S"}) h.add_gas_channels()->set_name(n);
  registry_.onConnected("robot1", "127.0.0.1:1", kSerial, h, now());
  (void)console_.background();
  v1::Telemetry t;
  t.set_mode(v1::NAVIGATING);
  t.add_gas(25.04);
  t.add_gas(std::numeric_limits<double>::quiet_NaN());
  auto* a = t.add_active_alarms();
  a->set_channel_name("CH4");
  a->set_level(v1::GasAlarm::HIGH);
  a->set_value(25.04);
  a->set_unit("%LEL");
  auto* f = t.add_active_alarms();
  f->set_channel_name("H2S");
  f->set_level(v1::GasAlarm::SENSOR_FAULT);
  f->set_fault("no_data");
  registry_.onTelemetry("robot1", kSerial, t, now());
  const std::string s = console_.statusText("robot1");
  EXPECT_NE(s.find("| gas CH4 25 H2S -- |"), std::string::npos) << s;
  EXPECT_NE(s.find("| ALARM CH4 HIGH 25 %LEL | SENSOR FAULT H2S no_data"), std::string::npos) << s;
  EXPECT_TRUE(statusIsAlarm(registry_.snapshot("robot1", now())));
}

TEST(LineReader, ALineOverTheLimitIsDroppedAndReportedOnce) {
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const std::string in = "ok\n" + std::string(5000, 'a') + "\nnext\r\n" + std::string(10, 'b') + "\nlast";
  ASSERT_EQ(::write(fds[1], in.data(), in.size()), static_cast<ssize_t>(in.size()));
  ::close(fds[1]);
  StopFlag stop;
  LineReader reader(fds[0], stop, 8);
  std::string line;
  ASSERT_EQ(reader.nextLine(line, 1000), LineReader::Result::kData);
  EXPECT_EQ(line, "ok");
  EXPECT_EQ(reader.nextLine(line, 1000), LineReader::Result::kTooLong);  // 5000 bytes read in pieces: one report
  ASSERT_EQ(reader.nextLine(line, 1000), LineReader::Result::kData);
  EXPECT_EQ(line, "next\r");
  EXPECT_EQ(reader.nextLine(line, 1000), LineReader::Result::kTooLong);  // whole in the buffer, 10 > 8
  ASSERT_EQ(reader.nextLine(line, 1000), LineReader::Result::kData);
  EXPECT_EQ(line, "last");
  EXPECT_EQ(reader.nextLine(line, 1000), LineReader::Result::kEof);
  ::close(fds[0]);
}

// A Foxglove client's session (Options allow_drive / feeds_watchdog off): its
// teleop is the Teleop panel's, whose set-points lapse; `drive` would be
// re-sent until stop. And it does not vouch for the console thread.
TEST(ConsoleFoxgloveSession, RefusesDriveAndDoesNotFeedTheWatchdog) {
  StopFlag stop;
  ManualClock clock(stop);
  RobotRegistry registry;
  FakeSink sink(registry, clock);
  std::ostringstream out;
  Console::Options o;
  o.allow_drive = false;
  o.feeds_watchdog = false;
  Console c(registry, sink, out, stop, o);
  c.setClock(clock);
  v1::Hello h;
  h.set_robot_id("robot1");
  registry.onConnected("robot1", "127.0.0.1:1", kSerial, h, clock.nowNs());
  (void)c.background();
  EXPECT_EQ(sink.alive_calls, 0);
  EXPECT_FALSE(c.execute("drive 0.3 0", 1));
  EXPECT_NE(out.str().find("drive: not from a Foxglove session: publish geometry_msgs/Twist on /<robot>/cmd_vel"),
            std::string::npos)
      << out.str();
  EXPECT_FALSE(sink.teleop_active);
  EXPECT_FALSE(c.execute("try drive 0.3 0", 2) && sink.teleop_active);
  EXPECT_FALSE(sink.teleop_active);
  EXPECT_TRUE(c.execute("stop", 3));  // stop always works
}
