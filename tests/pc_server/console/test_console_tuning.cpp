// The console's tuning commands (gains, tune) against a real RobotCore: the
// commands go to the robot's decision core, its Acks and events come back
// through the registry as over the link (docs/tuning.md).
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>

#include "pc_server/link/command_sink.hpp"
#include "pc_server/console/console.hpp"
#include "pc_server/link/robot_registry.hpp"
#include "pc_server/operator/stop_flag.hpp"
#include "shared/robot/robot_core.hpp"
#include "shared/config/control_config.hpp"
#include "shared/net/gains_proto.hpp"
#include "shared/util/clock.hpp"
#include "tests/support/paths.hpp"

using namespace inspect;
using namespace inspect::server;
namespace fs = std::filesystem;

namespace {

constexpr uint64_t kTuningSerial = 1;
std::string src(const std::string& rel) { return inspect::test::srcPath(rel); }

/// The robot's decision core behind the sink: one 100 Hz tick after each command.
class CoreSink : public CommandSink {
 public:
  explicit CoreSink(RobotRegistry& r) : registry_(r) {
    control_ = config::loadControlConfigFile(src("config/control.yaml"));
    core_ = std::make_unique<robot::RobotCore>(robot_, safety_, control_, config::loadScheduler(control_));
    frame_.ultrasonic_mm.fill(serial::kNoEcho);
    core_->onSerialState(true, 0.0);
    core_->onLinkUp(0.0);
    tick();
  }
  void connect() {
    v1::Hello h;
    h.set_robot_id("robot1");
    net::toProto(core_->gains(), *h.mutable_gains());
    h.set_gains_version(core_->gainsVersion());
    h.set_fis_name("fuzzy_pid");
    registry_.onConnected("robot1", "127.0.0.1:1", kTuningSerial, h, monoNowNs());
  }
  uint64_t setTeleop(const std::string&, double, double, double) override { return 0; }
  void clearTeleop(const std::string&) override {}
  void consoleAlive() override {}
  uint64_t sendCommand(const std::string& robot, v1::Command cmd) override {
    const auto s = registry_.snapshot(robot, monoNowNs());
    if (!s || !s->connected) return 0;
    cmd.set_id(++next_id_);
    registry_.onAck(robot, kTuningSerial, core_->onCommand(cmd, t_));
    tick();
    return next_id_;
  }
  void tick() {
    t_ += 0.01;
    frame_.mcu_time_ms = static_cast<uint32_t>(t_ * 1000.0 + 0.5);
    core_->onLinkActivity(t_);
    core_->onSensorFrame(frame_, t_);
    for (auto& e : core_->takeEvents()) {
      v1::Event ev;
      ev.set_kind(e.kind);
      ev.set_text(e.text);
      if (e.gains) {
        *ev.mutable_gains() = *e.gains;
        ev.set_gains_version(e.gains_version);
      }
      registry_.onEvent("robot1", kTuningSerial, ev, monoNowNs());
    }
  }
  robot::RobotCore& core() { return *core_; }

 private:
  RobotRegistry& registry_;
  config::RobotConfig robot_;
  robot::SafetyParams safety_;
  config::ControlConfig control_;
  std::unique_ptr<robot::RobotCore> core_;
  serial::SensorFrame frame_;
  double t_ = 0.0;
  uint64_t next_id_ = 0;
};

class ConsoleTuningTest : public ::testing::Test {
 protected:
  ConsoleTuningTest() : sink_(registry_), console_(registry_, sink_, out_, stop_, options()) {
    dir_ = fs::temp_directory_path() / ("console_tuning_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    console_.setTuningPaths(src("config/robot.yaml"), src("config/control.yaml"), (dir_ / "tuning").string());
    sink_.connect();
    (void)console_.background();
  }
  ~ConsoleTuningTest() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  static Console::Options options() {
    Console::Options o;
    o.ack_timeout_s = 0.2;
    return o;
  }
  std::pair<bool, std::string> run(const std::string& line) {
    out_.str("");
    const bool ok = console_.execute(line, 1);
    return {ok, out_.str()};
  }

  RobotRegistry registry_;
  CoreSink sink_;
  std::ostringstream out_;
  StopFlag stop_;
  Console console_;
  fs::path dir_;
};

#define EXPECT_HAS(text, part) EXPECT_NE((text).find(part), std::string::npos) << (text)

}  // namespace

TEST_F(ConsoleTuningTest, SetPushAndRevertReachTheRobotWithVersions) {
  auto [ok, out] = run("gains show");
  ASSERT_TRUE(ok) << out;
  EXPECT_HAS(out, "robot1 v0");
  EXPECT_HAS(out, "kp                9            9            9");
  std::tie(ok, out) = run("gains set kp=12 ki=3");
  ASSERT_TRUE(ok) << out;
  EXPECT_HAS(out, "kp=12 ki=3");
  std::tie(ok, out) = run("gains set a2 0.5");
  EXPECT_FALSE(ok);
  EXPECT_EQ(out, "gains: a2 = 0.5 is outside [-20, 0] (nothing changed)\n");
  std::tie(ok, out) = run("gains set kq=1");
  EXPECT_FALSE(ok);
  EXPECT_HAS(out, "unknown gain 'kq'");
  std::tie(ok, out) = run("gains set kp=abc");
  EXPECT_FALSE(ok);
  EXPECT_HAS(out, "'abc' is not a number");

  std::tie(ok, out) = run("gains push");
  ASSERT_TRUE(ok) << out;
  EXPECT_HAS(out, "robot1: gains v1 accepted (in force from the next control tick)\n");
  EXPECT_EQ(sink_.core().gainsVersion(), 1u);
  EXPECT_DOUBLE_EQ(sink_.core().gains().fuzzy.base.kp, 12.0);
  std::tie(ok, out) = run("gains show");
  EXPECT_HAS(out, "robot1 v1");

  std::tie(ok, out) = run("gains revert");
  ASSERT_TRUE(ok) << out;
  EXPECT_HAS(out, "reverting robot1 to the set of v0");
  EXPECT_HAS(out, "robot1: gains v2 accepted");
  EXPECT_DOUBLE_EQ(sink_.core().gains().fuzzy.base.kp, 9.0);
  EXPECT_DOUBLE_EQ(sink_.core().gains().fuzzy.base.ki, 2.0);

  std::tie(ok, out) = run("gains push robot9");
  EXPECT_FALSE(ok);
  EXPECT_HAS(out, "gains: robot9 is not connected\n");
  std::tie(ok, out) = run("gains frobnicate");
  EXPECT_FALSE(ok);
  EXPECT_HAS(out, "unknown subcommand 'frobnicate'");
}

TEST_F(ConsoleTuningTest, ExportImportRoundTripsWithTheFuzzySystem) {
  ASSERT_TRUE(run("gains set kp=7.25 a3=-0.75").first);
  const std::string f = (dir_ / "mine.yaml").string();
  auto [ok, out] = run("gains export " + f);
  ASSERT_TRUE(ok) << out;
  EXPECT_TRUE(fs::exists(dir_ / "mine.fis"));
  ASSERT_TRUE(run("gains set paper").first);
  std::tie(ok, out) = run("gains import " + f);
  ASSERT_TRUE(ok) << out;
  EXPECT_HAS(out, "kp=7.25");
  EXPECT_HAS(out, "a3=-0.75");
  std::tie(ok, out) = run("gains import " + (dir_ / "missing.yaml").string());
  EXPECT_FALSE(ok);
  EXPECT_HAS(out, "missing.yaml");
}

TEST_F(ConsoleTuningTest, TuneRefusesBadOptionsNamingThem) {
  for (const auto& [line, part] : std::vector<std::pair<std::string, std::string>>{
           {"tune frob", "'frob' is not key=value"},
           {"tune evals=abc", "evals=abc: expected a number in [10, 100000]"},
           {"tune evals=5", "evals=5: expected a number"},
           {"tune params=kp,kx", "unknown gain 'kx'"},
           {"tune ref=spiral", "ref=spiral: expected circle, line or waypoints"},
           {"tune plant=/nonexistent/plant.yaml", "plant=/nonexistent/plant.yaml"},
           {"tune start=tuned", "nothing tuned yet"},
           {"tune colour=red", "unknown option 'colour'"}}) {
    const auto [ok, out] = run(line);
    EXPECT_FALSE(ok) << line;
    EXPECT_HAS(out, part);
  }
}

TEST_F(ConsoleTuningTest, AShortTuneComparesWritesASessionAndSetsTheWorkingGains) {
  auto [ok, out] = run("tune evals=24 variations=1 seeds=1 params=kp,ki threads=2");
  ASSERT_TRUE(ok) << out;
  EXPECT_HAS(out, "tune: done: 24 evaluations");
  EXPECT_HAS(out, "PID (paper)");
  EXPECT_HAS(out, "fuzzy-PID (tuned)");
  EXPECT_HAS(out, "max position error (m)");
  EXPECT_HAS(out, "the working gains are now the tuned set");
  ASSERT_EQ(std::distance(fs::directory_iterator(dir_ / "tuning"), fs::directory_iterator()), 1);
  const fs::path session = fs::directory_iterator(dir_ / "tuning")->path();
  EXPECT_TRUE(fs::exists(session / "summary.md"));
  EXPECT_TRUE(fs::exists(session / "results.json"));
  EXPECT_TRUE(fs::exists(session / "gains_tuned.yaml"));
  std::tie(ok, out) = run("gains show");
  EXPECT_HAS(out, "tuned");
  // Only kp and ki were tuned: the rest is the paper's.
  std::tie(ok, out) = run("gains push");
  ASSERT_TRUE(ok) << out;
  EXPECT_DOUBLE_EQ(sink_.core().gains().fuzzy.ke, 0.9);
  EXPECT_EQ(sink_.core().gainsVersion(), 1u);
}
