// The server's recorder on real files: runs started by the console and by a
// track command, what goes into the MCAP file and the catalog, and the
// summary figures.
#include <gtest/gtest.h>

#include "tests/support/null_command_sink.hpp"

#include "tests/support/postgres_server.hpp"

#include <filesystem>
#include <sstream>

#include "pc_server/console/console.hpp"
#include "pc_server/recording/fleet_presence.hpp"
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

/// A server `id`'s recording in `dir`, its catalog the PostgreSQL database at `url`.
RecordingConfig sharedCatalogIn(const fs::path& dir, const std::string& url, const std::string& id) {
  RecordingConfig c = recordingIn(dir);
  c.catalog = url;
  c.server_id = id;
  return c;
}

using NullSink = inspect::test::NullCommandSink;

/// An operator's console on a recorder (commands go nowhere).
struct OperatorConsole {
  explicit OperatorConsole(Recorder* r) { console.setRecorder(r); }
  ~OperatorConsole() { console.setRecorder(nullptr); }
  RobotRegistry registry;
  NullSink sink;
  std::ostringstream out;
  StopFlag stop;
  Console console{registry, sink, out, stop};
};

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

TEST(Recorder, ServersSharingACatalogOnPostgresKeepTheirOwnRuns) {
  // Two servers' recorders, each with its runs directory, one PostgreSQL catalog.
  TempRuns tmp_a, tmp_b;
  const std::string url = inspect::test::freshPostgresDatabase("recorder_fleet");
  auto config = [&](const fs::path& dir, const std::string& id) { return sharedCatalogIn(dir, url, id); };
  auto a = std::make_unique<Recorder>(config(tmp_a.dir, "ops-a"), "test");
  Recorder b(config(tmp_b.dir, "ops-b"), "test");
  const std::string ra = a->start("robot1", "north wing");
  const std::string rb = b.start("robot2", "south wing");
  b.onEnvelope("robot2", "127.0.0.1:2", telemetry(0.5, 2.0, 1), true, monoNowUs());
  EXPECT_TRUE(fs::exists(tmp_a.dir / ra / "run.mcap"));
  EXPECT_TRUE(fs::exists(tmp_b.dir / rb / "run.mcap"));

  RobotRegistry registry;
  NullSink sink;
  std::ostringstream out;
  StopFlag stop;
  Console console(registry, sink, out, stop);
  console.setRecorder(a.get());
  ASSERT_TRUE(console.execute("runs", 1));
  EXPECT_NE(out.str().find(ra), std::string::npos) << out.str();
  EXPECT_EQ(out.str().find(rb), std::string::npos) << "another server's run in plain `runs`: " << out.str();
  EXPECT_NE(out.str().find("1 run\n"), std::string::npos) << out.str();
  out.str("");
  b.catalog().upsertServer({"ops-b", "ops-b:7600", tmp_b.dir.string(), "test", catalog::Time{}, catalog::Time{}});
  ASSERT_TRUE(console.execute("runs --fleet", 2));
  EXPECT_NE(out.str().find(rb), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("ops-b @ops-b:7600"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("2 runs"), std::string::npos) << out.str();

  // ops-a stops; a run it left open (as a killed server would) is ended
  // when it starts again, ops-b's running run is not.
  console.setRecorder(nullptr);
  a.reset();
  EXPECT_EQ(b.catalog().run(ra).value().info.outcome, "stopped");
  auto left = catalog::Catalog::open(url);
  left.setServerId("ops-a");
  const std::string open_run = left.startRun({"robot1", "killed", "", "{}", "test", "", std::nullopt, ""}).id;
  Recorder a2(config(tmp_a.dir, "ops-a"), "test");
  EXPECT_NE(a2.startupReport().find(open_run + ": marked incomplete"), std::string::npos) << a2.startupReport();
  EXPECT_EQ(a2.startupReport().find(rb), std::string::npos) << a2.startupReport();
  EXPECT_EQ(b.catalog().run(rb).value().info.outcome, "");
  EXPECT_EQ(b.activeRun("robot2"), rb);
  EXPECT_EQ(b.stop("robot2"), rb);
  b.catalog();  // b's spool written through: what another server reads
  EXPECT_EQ(a2.catalog().run(rb).value().info.outcome, "stopped");
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
    NullSink sink;
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

TEST(FleetPresence, RobotsOfASilentServerAreNotShownOnline) {
  const auto now = catalog::parseIsoUtc("2026-12-06T08:30:00Z").value();
  std::vector<catalog::ServerInfo> servers(2);
  servers[0].id = "ops-a";
  servers[0].attach = "ws://ops-a:8765";
  servers[0].seen = now - std::chrono::seconds(1);
  servers[1].id = "ops-b";
  servers[1].attach = "ops-b:7600";
  servers[1].seen = now - std::chrono::seconds(42);  // killed, or cut off
  std::vector<catalog::RobotPresence> robots(3);
  robots[0] = {"robot1", "ops-a", true, "TELEOP", 3.2, -1.25, now};
  robots[1] = {"robot2", "ops-b", true, "IDLE", std::nullopt, std::nullopt, now - std::chrono::seconds(42)};
  robots[2] = {"robot3", "ops-a", false, "", std::nullopt, std::nullopt, now};
  const std::string t = fleetTable(robots, servers, now);
  EXPECT_NE(t.find("robot1           online                   TELEOP     (3.20, -1.25)    ops-a        ws://ops-a:8765"),
            std::string::npos) << t;
  EXPECT_NE(t.find("robot2           unknown (server silent 42 s)"), std::string::npos) << t;
  EXPECT_NE(t.find("ops-b:7600"), std::string::npos) << t;
  EXPECT_NE(t.find("robot3           offline"), std::string::npos) << t;
  EXPECT_EQ(fleetTable({}, servers, now), "no robot in the fleet's catalog yet\n");

  RobotSnapshot snap;
  snap.id = "robot1";
  snap.connected = true;
  snap.has_telemetry = true;
  snap.telemetry.set_mode(v1::TELEOP);
  snap.telemetry.mutable_pose()->set_x_m(3.2);
  snap.telemetry.mutable_pose()->set_y_m(-1.25);
  RobotSnapshot never;
  never.id = "robot9";
  const auto p = presenceOf({snap, never}, "ops-a", now);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_TRUE(p[0].online);
  EXPECT_EQ(p[0].mode, "TELEOP");
  EXPECT_EQ(p[0].x_m, 3.2);
  EXPECT_EQ(p[0].server, "ops-a");
  EXPECT_FALSE(p[1].online);
  EXPECT_FALSE(p[1].x_m.has_value());  // no telemetry: where is unknown, not (0, 0)
}

TEST(Recorder, AnOperatorOnEitherServerSeesTheFleetsRobotsOnPostgres) {
  TempRuns tmp_a, tmp_b;
  const std::string url = inspect::test::freshPostgresDatabase("recorder_presence");
  auto config = [&](const fs::path& dir, const std::string& id) { return sharedCatalogIn(dir, url, id); };
  Recorder a(config(tmp_a.dir, "ops-a"), "test"), b(config(tmp_b.dir, "ops-b"), "test");
  const auto now = std::chrono::system_clock::now();
  a.notePresence({"ops-a", "ws://ops-a:8765", tmp_a.dir.string(), "test", now, now},
                 {{"robot1", "ops-a", true, "TELEOP", 1.5, 2.5, now}});
  b.notePresence({"ops-b", "ops-b:7600", tmp_b.dir.string(), "test", now, now},
                 {{"robot2", "ops-b", true, "IDLE", 0.0, 0.0, now}});
  b.catalog();  // b's rows written

  OperatorConsole oc(&a);
  auto& console = oc.console;
  auto& out = oc.out;
  ASSERT_TRUE(console.execute("robots --fleet", 1)) << out.str();
  EXPECT_NE(out.str().find("robot1           online"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("ws://ops-a:8765"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("robot2           online"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("ops-b:7600"), std::string::npos) << out.str();
}

TEST(Recorder, RobotsFleetNeedsASharedCatalog) {
  TempRuns tmp;
  Recorder rec(recordingIn(tmp.dir), "test");
  OperatorConsole oc(&rec);
  auto& console = oc.console;
  auto& out = oc.out;
  EXPECT_FALSE(console.execute("robots --fleet", 1));
  EXPECT_NE(out.str().find("robots: --fleet needs a catalog that several servers share"), std::string::npos)
      << out.str();
}

TEST(Recorder, AnotherServersRunIsReadFromTheSharedRunsRootOnPostgres) {
  TempRuns tmp_a, tmp_b, shared;
  const std::string url = inspect::test::freshPostgresDatabase("recorder_shared");
  auto with_shared = [&](const fs::path& dir, const std::string& id) {
    RecordingConfig c = sharedCatalogIn(dir, url, id);
    c.shared_runs = shared.dir.string();
    return c;
  };
  Recorder a(with_shared(tmp_a.dir, "ops-a"), "test");
  const std::string rb = [&] {
    Recorder b(with_shared(tmp_b.dir, "ops-b"), "test");
    EXPECT_EQ(b.runsRoot(), fs::absolute(shared.dir / "ops-b").lexically_normal().string());
    const std::string id = b.start("robot2", "south wing");
    for (int i = 0; i < 20; ++i)
      b.onEnvelope("robot2", "127.0.0.1:2", telemetry(0.05 * i, 2.0, 1), true, monoNowUs() + 20000ull * i);
    b.stop("robot2");
    EXPECT_TRUE(b.waitForCopies(20.0));
    return id;
  }();  // ops-b is gone: its own runs directory is not reachable from ops-a
  fs::remove_all(tmp_b.dir);
  EXPECT_TRUE(fs::exists(shared.dir / "ops-b" / rb / "run.mcap"));
  EXPECT_FALSE(fs::exists(shared.dir / "ops-b" / (rb + ".partial")));

  OperatorConsole oc(&a);
  auto& console = oc.console;
  auto& out = oc.out;
  ASSERT_TRUE(console.execute("export " + rb + " csv", 1)) << out.str();
  EXPECT_NE(out.str().find(rb + ": exported"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find((shared.dir / "ops-b" / rb / "csv").string()), std::string::npos) << out.str();
  const auto d = a.catalog().run(rb);
  ASSERT_TRUE(d);
  bool listed = false;
  for (const auto& f : d->files) listed |= f.kind == "shared" && f.bytes > 0;
  EXPECT_TRUE(listed) << "the shared copy is not among the run's files";

  // Without a shared runs root, another server's run is a clear refusal.
  TempRuns tmp_c;
  Recorder c(sharedCatalogIn(tmp_c.dir, url, "ops-c"), "test");
  console.setRecorder(&c);
  out.str("");
  EXPECT_FALSE(console.execute("export " + rb + " csv", 2));
  EXPECT_NE(out.str().find("was recorded by server ops-b, whose files this server cannot reach"), std::string::npos)
      << out.str();
}
