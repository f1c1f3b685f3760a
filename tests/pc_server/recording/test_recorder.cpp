// The server's recorder on real files: runs started by the console and by a
// track command, what goes into the MCAP file and the catalog, and the
// summary figures.
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>

#include "pc_server/console/console.hpp"
#include "pc_server/recording/recorder.hpp"
#include "pc_server/recording/run_stats.hpp"
#include "shared/record/mcap_writer.hpp"
#include "shared/util/clock.hpp"

using namespace inspect;
using namespace inspect::server;
namespace fs = std::filesystem;

namespace {
struct TempRuns {
  fs::path dir = fs::temp_directory_path() / ("inspect-recorder-" + std::to_string(::getpid()) + "-" +
                                              std::to_string(monoNowNs()));
  ~TempRuns() { fs::remove_all(dir); }
};

RecordingConfig recordingIn(const fs::path& dir) {
  RecordingConfig c;
  c.dir = dir.string();
  return c;
}

v1::Envelope telemetry(double x, double person, double gas, v1::Mode mode = v1::IDLE, double err = 0) {
  v1::Envelope e;
  auto* t = e.mutable_telemetry();
  t->set_robot_time_us(static_cast<uint64_t>(x * 1e6));
  t->mutable_pose()->set_x_m(x);
  t->set_nearest_person_m(person);
  t->add_gas(gas);
  t->set_mode(mode);
  t->set_position_error_m(err);
  e.set_send_time_us(monoNowUs());
  return e;
}
}  // namespace

TEST(RunStats, SumsARunUp) {
  RunStats s;
  v1::Telemetry t;
  for (int i = 0; i <= 10; ++i) {
    t.set_robot_time_us(static_cast<uint64_t>(i) * 100000);
    t.mutable_pose()->set_x_m(0.1 * i);
    t.set_nearest_person_m(i == 5 ? 0.8 : (i == 7 ? -1 : 2.0));
    t.clear_gas();
    t.add_gas(i);
    t.set_mode(i >= 8 ? v1::TRACKING : v1::IDLE);
    t.set_position_error_m(i >= 8 ? 0.03 : 9.0);
    s.add(t);
  }
  t.mutable_pose()->set_x_m(50);  // an odometry jump is not distance
  t.set_robot_time_us(1'100'000);
  s.add(t);
  const auto f = s.figures();
  EXPECT_NEAR(f.duration_s, 1.1, 1e-9);
  EXPECT_NEAR(f.distance_m, 1.0, 1e-9);
  EXPECT_DOUBLE_EQ(f.min_person_m, 0.8);
  EXPECT_DOUBLE_EQ(f.max_position_error_m, 0.03);
  EXPECT_NEAR(f.rms_position_error_m, 0.03, 1e-12);
  ASSERT_EQ(f.gas.size(), 1u);
  EXPECT_DOUBLE_EQ(f.gas[0].max, 10);
  EXPECT_NEAR(f.gas[0].mean, 65.0 / 12, 1e-9);  // 0..10, then 10 again
}

TEST(Recorder, ConsoleRunAndTrackRunAreRecordedAndListed) {
  TempRuns tmp;
  std::string first, second;
  {
    Recorder rec(recordingIn(tmp.dir), "test");
    first = rec.start("robot1", "manual");
    EXPECT_THROW(rec.start("robot1", "again"), std::runtime_error);
    for (int i = 0; i < 20; ++i) rec.onEnvelope("robot1", "127.0.0.1:1", telemetry(0.05 * i, 1.5, 3), true, monoNowUs());
    rec.onEnvelope("robot1", "127.0.0.1:2", telemetry(1.0, 1.2, 4), true, monoNowUs());  // a reconnect
    ASSERT_EQ(rec.stop("robot1"), first);
    EXPECT_FALSE(rec.stop("robot1").has_value());

    // A track command starts a run by itself; its COMPLETED ack ends it.
    v1::Envelope cmd;
    cmd.mutable_command()->set_id(77);
    cmd.mutable_command()->mutable_track()->mutable_line()->set_length_m(1);
    rec.onEnvelope("robot1", "127.0.0.1:2", cmd, false, monoNowUs());
    const auto active = rec.activeRun("robot1");
    ASSERT_TRUE(active.has_value());
    second = *active;
    auto tracking = telemetry(0.5, -1, 1, v1::TRACKING, 0.02);
    tracking.mutable_telemetry()->set_track_controller("fuzzy_pid");
    tracking.mutable_telemetry()->set_kp(9.5);
    rec.onEnvelope("robot1", "127.0.0.1:2", tracking, true, monoNowUs());
    v1::Envelope ack;
    ack.mutable_ack()->set_command_id(77);
    ack.mutable_ack()->set_status(v1::Ack::COMPLETED);
    rec.onEnvelope("robot1", "127.0.0.1:2", ack, true, monoNowUs());
    EXPECT_FALSE(rec.activeRun("robot1").has_value());

    const auto d1 = rec.catalog().run(first);
    ASSERT_TRUE(d1 && d1->summary);
    EXPECT_EQ(d1->info.outcome, "stopped");
    EXPECT_NEAR(d1->summary->distance_m, 1.0, 1e-9);  // 0 .. 0.95, then 1.0
    EXPECT_DOUBLE_EQ(*d1->summary->min_person_m, 1.2);
    EXPECT_GE(d1->event_count, 3);  // start, reconnect, end
    const auto d2 = rec.catalog().run(second);
    ASSERT_TRUE(d2 && d2->summary);
    EXPECT_EQ(d2->info.outcome, "completed");
    EXPECT_EQ(d2->info.name, "track");
    EXPECT_NE(d2->info.gains_json.find(R"("controller":"fuzzy_pid")"), std::string::npos) << d2->info.gains_json;
    EXPECT_NE(d2->info.gains_json.find(R"("kp":9.5)"), std::string::npos) << d2->info.gains_json;
    EXPECT_EQ(d1->info.gains_json, "{}");  // never tracked
    EXPECT_DOUBLE_EQ(d2->summary->track_max_pos_err_m.value_or(-1), 0.02);

    // The console lists and shows them.
    RobotRegistry registry;
    struct NullSink : CommandSink {
      uint64_t setTeleop(const std::string&, double, double, double) override { return 0; }
      void clearTeleop(const std::string&) override {}
      uint64_t sendCommand(const std::string&, v1::Command) override { return 0; }
      void consoleAlive() override {}
    } sink;
    std::ostringstream out;
    StopFlag stop;
    Console console(registry, sink, out, stop);
    console.setRecorder(&rec);
    EXPECT_TRUE(console.execute("runs", 1));
    EXPECT_NE(out.str().find(first), std::string::npos) << out.str();
    EXPECT_NE(out.str().find("completed"), std::string::npos) << out.str();
    EXPECT_NE(out.str().find("2 runs"), std::string::npos) << out.str();
    EXPECT_TRUE(console.execute("run show " + first, 2));
    EXPECT_NE(out.str().find("distance 1.00 m"), std::string::npos) << out.str();
    EXPECT_FALSE(console.execute("run show nope", 3));
  }
  // The MCAP file of the first run is complete (the repair leaves it as it is).
  const auto r = record::repairMcap((tmp.dir / first / "run.mcap").string());
  EXPECT_TRUE(r.was_complete);
  EXPECT_GE(r.messages_kept, 21u + 3u);  // telemetry + server events
}

// A run left open by a killed server (marked incomplete, MCAP repaired at the
// next start) is tested through the real programs: RecordingStack.*.
