// Run catalog on both engines: real SQLite files in a temporary directory and
// real PostgreSQL databases on the suite's server (tests/support/pg_cluster.sh).
// On both (CatalogTest, one instance per engine): reopening, run ids, runs,
// events, alarms, summaries, files, filters, tuning sessions, gains pushes,
// incomplete runs, concurrent writers. SQLite's own (SqliteCatalogTest):
// WAL, migrations (v1 -> latest, v3 -> latest, refusing a newer schema), a
// SIGKILL during a run, the sqlite3 shell, bad files. PostgreSQL's own
// (PostgresCatalogTest): two servers' connections sharing one database,
// refusing a newer schema or a foreign database, an unreachable server
// named without its password. And the time format.
#include <gtest/gtest.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <thread>

#include "shared/catalog/catalog.hpp"
#include "shared/catalog/sql_backend.hpp"
#include "tests/support/postgres_server.hpp"
#include "tests/support/sql_query.hpp"

using namespace inspect::catalog;
namespace fs = std::filesystem;
using std::chrono::milliseconds;

namespace {

Time at(const char* iso) { return parseIsoUtc(iso).value(); }

RunStart runOf(const std::string& robot, const std::string& name, Time start) {
  RunStart r;
  r.robot = robot;
  r.name = name;
  r.route = "routes/corridor.yaml";
  r.gains_json = R"({"kp":1.5})";
  r.software_version = "0.1.0";
  r.dir = "runs/" + name;
  r.start = start;
  return r;
}

using inspect::test::rawQuery;

// The CatalogError message of `f`, "" if it does not throw one.
template <class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const CatalogError& e) {
    return e.what();
  }
  return "";
}

class SqliteCatalogTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = info->name();
    for (char& c : name) if (c == '/') c = '_';
    dir_ = fs::temp_directory_path() / ("catalog_test_" + std::to_string(::getpid()) + "_" + name);
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    path_ = (dir_ / "catalog.sqlite").string();
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path dir_;
  std::string path_;  // the SQLite file, or the PostgreSQL database's URL (CatalogTest)
  const Time t0_ = at("2026-11-22T08:30:15.250Z");
};

enum class Engine { kSqlite, kPostgres };

/// The same tests on each engine: path_ is a SQLite file or a fresh PostgreSQL database.
class CatalogTest : public SqliteCatalogTest, public ::testing::WithParamInterface<Engine> {
 protected:
  void SetUp() override {
    SqliteCatalogTest::SetUp();
    if (GetParam() == Engine::kPostgres)
      path_ = inspect::test::freshPostgresDatabase(::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
};

/// PostgreSQL's own: path_ is a fresh database.
class PostgresCatalogTest : public SqliteCatalogTest {
 protected:
  void SetUp() override {
    SqliteCatalogTest::SetUp();
    path_ = inspect::test::freshPostgresDatabase(::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
};

TEST_F(SqliteCatalogTest, CreatesWalDatabaseAtLatestVersion) {
  auto cat = Catalog::open(path_);
  EXPECT_TRUE(fs::exists(path_));
  EXPECT_EQ(cat.schemaVersion(), static_cast<int>(schemaMigrations().size()));
  EXPECT_EQ(cat.integrityCheck(), "ok");
  EXPECT_EQ(rawQuery(path_, "PRAGMA journal_mode"), std::vector<std::string>{"wal"});
  EXPECT_EQ(rawQuery(path_, "SELECT name FROM sqlite_master WHERE type IN ('table', 'view') ORDER BY name"),
            (std::vector<std::string>{"alarms", "events", "gains_pushes", "robot_presence", "robots", "run_files",
                                      "run_gas", "run_overview", "run_summary", "runs", "servers",
                                      "spool_applied", "tuning_sessions"}));
}

TEST_P(CatalogTest, ReopeningKeepsDataAndVersion) {
  std::string id;
  {
    auto cat = Catalog::open(path_);
    id = cat.startRun(runOf("robot1", "a", t0_)).id;
  }
  auto cat = Catalog::open(path_);
  EXPECT_EQ(cat.schemaVersion(), static_cast<int>(schemaMigrations().size()));
  const auto runs = cat.listRuns();
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].id, id);
}

TEST_F(SqliteCatalogTest, UpgradesVersion1ToLatest) {
  std::string id;
  {
    auto v1 = Catalog::open(path_, schemaMigrations().first(1));
    EXPECT_EQ(v1.schemaVersion(), 1);
    id = v1.startRun(runOf("robot1", "old", t0_)).id;
    v1.addEvent(id, "robot1", t0_ + milliseconds(10), "note", "before the upgrade");
    ASSERT_TRUE(v1.endRun(id, "completed", t0_ + milliseconds(5000)));
  }
  EXPECT_EQ(rawQuery(path_, "SELECT count(*) FROM sqlite_master WHERE name = 'run_summary'"),
            std::vector<std::string>{"0"});

  auto cat = Catalog::open(path_);
  EXPECT_EQ(cat.schemaVersion(), static_cast<int>(schemaMigrations().size()));
  Summary s;
  s.duration_s = 5;
  s.gas = {{"CH4", "ppm", 12, 3}};
  cat.setSummary(id, s);
  const auto d = cat.run(id);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->info.name, "old");
  EXPECT_EQ(d->info.outcome, "completed");
  EXPECT_EQ(d->event_count, 1);
  ASSERT_TRUE(d->summary);
  ASSERT_EQ(d->summary->gas.size(), 1u);
  EXPECT_EQ(cat.integrityCheck(), "ok");
}

TEST_F(SqliteCatalogTest, UpgradesVersion3ToLatestWithTheTuningTables) {
  std::string id;
  {
    auto v3 = Catalog::open(path_, schemaMigrations().first(3));
    EXPECT_EQ(v3.schemaVersion(), 3);
    id = v3.startRun(runOf("robot1", "before tuning", t0_)).id;
  }
  EXPECT_EQ(rawQuery(path_, "SELECT count(*) FROM sqlite_master WHERE name IN ('tuning_sessions', 'gains_pushes')"),
            std::vector<std::string>{"0"});

  auto cat = Catalog::open(path_);
  EXPECT_EQ(cat.schemaVersion(), static_cast<int>(schemaMigrations().size()));
  EXPECT_EQ(rawQuery(path_, "SELECT count(*) FROM sqlite_master WHERE name IN ('tuning_sessions', 'gains_pushes')"),
            std::vector<std::string>{"2"});
  EXPECT_EQ(cat.run(id).value().info.name, "before tuning");
  EXPECT_TRUE(cat.listTuningSessions().empty());
  EXPECT_TRUE(cat.listGainsPushes("").empty());
  TuningSession s;
  s.id = "after-upgrade";
  s.created = t0_;
  cat.addTuningSession(s);
  EXPECT_TRUE(cat.tuningSession("after-upgrade"));
  EXPECT_EQ(cat.integrityCheck(), "ok");
}

TEST_F(SqliteCatalogTest, RefusesANewerSchema) {
  { auto cat = Catalog::open(path_); }
  // A program that knows only version 1 must not touch a later catalog.
  const std::string older = errorOf([&] { Catalog::open(path_, schemaMigrations().first(1)); });
  EXPECT_NE(older.find(path_), std::string::npos) << older;
  EXPECT_NE(older.find("newer program"), std::string::npos) << older;

  const int future = static_cast<int>(schemaMigrations().size()) + 1;
  rawQuery(path_, "PRAGMA user_version = " + std::to_string(future));
  const std::string err = errorOf([&] { Catalog::open(path_); });
  EXPECT_NE(err.find("schema version " + std::to_string(future)), std::string::npos) << err;
  // Refusing did not change the file.
  EXPECT_EQ(rawQuery(path_, "PRAGMA user_version"), std::vector<std::string>{std::to_string(future)});
}

TEST_P(CatalogTest, RunIdsAreUniqueWithinASecond) {
  auto cat = Catalog::open(path_);
  const auto a = cat.startRun(runOf("robot1", "a", t0_));
  const auto b = cat.startRun(runOf("robot1", "b", t0_ + milliseconds(300)));
  const auto c = cat.startRun(runOf("robot1", "c", t0_));
  const auto other = cat.startRun(runOf("robot 2/x", "d", t0_));
  EXPECT_EQ(a.id, "20261122-083015-robot1");
  EXPECT_EQ(b.id, "20261122-083015-robot1-2");
  EXPECT_EQ(c.id, "20261122-083015-robot1-3");
  EXPECT_EQ(other.id, "20261122-083015-robot_2_x");
  EXPECT_EQ(other.robot, "robot 2/x");
  EXPECT_LT(a.rowid, b.rowid);
  EXPECT_LT(b.rowid, c.rowid);
  EXPECT_FALSE(errorOf([&] { cat.startRun(runOf("", "x", t0_)); }).empty());
}

TEST_P(CatalogTest, StartAndEndRuns) {
  auto cat = Catalog::open(path_);
  cat.upsertRobot("robot1", "0.1.0", t0_ - milliseconds(60000));
  const auto r = cat.startRun(runOf("robot1", "night", t0_));
  EXPECT_EQ(cat.activeRun("robot1").value().id, r.id);
  EXPECT_FALSE(cat.activeRun("robot9"));

  EXPECT_NE(errorOf([&] { cat.endRun(r.id, "exploded", t0_); }).find("unknown outcome"), std::string::npos);
  EXPECT_NE(errorOf([&] { cat.endRun("nope", "completed", t0_); }).find("no run 'nope'"), std::string::npos);
  EXPECT_TRUE(cat.endRun(r.id, "stopped", t0_ + milliseconds(90500)));
  EXPECT_FALSE(cat.endRun(r.id, "completed", t0_ + milliseconds(99000)));  // already ended: unchanged
  EXPECT_FALSE(cat.activeRun("robot1"));

  const auto d = cat.run(r.id).value();
  EXPECT_EQ(d.info.outcome, "stopped");
  EXPECT_EQ(d.info.end.value(), t0_ + milliseconds(90500));
  EXPECT_EQ(d.info.start, t0_);
  EXPECT_EQ(d.info.gains_json, R"({"kp":1.5})");
  EXPECT_EQ(d.info.route, "routes/corridor.yaml");
  EXPECT_EQ(d.info.dir, "runs/night");
  EXPECT_EQ(cat.run(std::to_string(r.rowid)).value().info.id, r.id);  // by rowid too
  EXPECT_FALSE(cat.run("20990101-000000-none"));

  // Robots: the first sighting stays, the version and last sighting follow upserts.
  cat.upsertRobot("robot1", "0.2.0", t0_ + milliseconds(100000));
  EXPECT_EQ(rawQuery(path_, "SELECT first_seen || ' ' || last_seen || ' ' || software_version FROM robots"),
            std::vector<std::string>{"2026-11-22T08:29:15.250Z 2026-11-22T08:31:55.250Z 0.2.0"});
  EXPECT_EQ(rawQuery(path_, "SELECT start_time || ' ' || end_time FROM runs"),
            std::vector<std::string>{"2026-11-22T08:30:15.250Z 2026-11-22T08:31:45.750Z"});
}

TEST_P(CatalogTest, EventsAlarmsSummaryAndFilesRoundTrip) {
  auto cat = Catalog::open(path_);
  const auto r = cat.startRun(runOf("robot1", "gas round", t0_));
  cat.addEvent(r.id, "robot1", t0_ + milliseconds(100), "connected", "");
  cat.addEvent(r.id, "robot1", t0_ + milliseconds(200), "disconnected", "link lost");
  cat.addEvent("", "robot1", t0_ + milliseconds(250), "note", "between runs");
  cat.addAlarm(r.id, "robot1", t0_ + milliseconds(300), "CH4", "alarm", "raised", 812.5, 3.25, -1.5);
  // SQLite: "FOREIGN KEY constraint failed"; PostgreSQL: "... violates foreign key constraint ...".
  std::string fk = errorOf([&] { cat.addEvent("nope", "robot1", t0_, "x", ""); });
  for (char& c : fk) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  EXPECT_NE(fk.find("foreign key"), std::string::npos) << fk;

  Summary s;
  s.duration_s = 95.5;
  s.distance_m = 42.25;
  s.min_person_m = 0.85;
  s.track_max_pos_err_m = 0.12;
  s.track_rms_pos_err_m = 0.04;
  s.track_max_angle_err_rad = 0.2;
  s.video_frames_received = 2850;
  s.video_frames_decoded = 2840;
  s.video_packets_lost = 7;
  s.gas = {{"CO", "ppm", 5, 1}, {"CH4", "ppm", 812.5, 120.25}};
  cat.setSummary(r.id, s);
  s.gas.pop_back();  // a second summary replaces the first, gas rows included
  s.gas[0].max = 6;
  s.min_person_m.reset();
  cat.setSummary(r.id, s);

  cat.addFile(r.id, "telemetry", "runs/gas/telemetry.csv", 100);
  cat.addFile(r.id, "video", "runs/gas/camera.mkv", 5000000);
  cat.addFile(r.id, "telemetry", "runs/gas/telemetry.csv", 2048);  // final size

  const auto d = cat.run(r.id).value();
  EXPECT_EQ(d.event_count, 2);
  EXPECT_EQ(d.alarm_count, 1);
  ASSERT_TRUE(d.summary);
  EXPECT_DOUBLE_EQ(d.summary->duration_s, 95.5);
  EXPECT_DOUBLE_EQ(d.summary->distance_m, 42.25);
  EXPECT_FALSE(d.summary->min_person_m);
  EXPECT_DOUBLE_EQ(d.summary->track_max_pos_err_m.value(), 0.12);
  EXPECT_DOUBLE_EQ(d.summary->track_rms_pos_err_m.value(), 0.04);
  EXPECT_DOUBLE_EQ(d.summary->track_max_angle_err_rad.value(), 0.2);
  EXPECT_EQ(d.summary->video_frames_received, 2850);
  EXPECT_EQ(d.summary->video_frames_decoded, 2840);
  EXPECT_EQ(d.summary->video_packets_lost, 7);
  ASSERT_EQ(d.summary->gas.size(), 1u);
  EXPECT_EQ(d.summary->gas[0].channel, "CO");
  EXPECT_EQ(d.summary->gas[0].unit, "ppm");
  EXPECT_DOUBLE_EQ(d.summary->gas[0].max, 6);
  EXPECT_DOUBLE_EQ(d.summary->gas[0].mean, 1);
  ASSERT_EQ(d.files.size(), 2u);
  EXPECT_EQ(d.files[0].path, "runs/gas/telemetry.csv");
  EXPECT_EQ(d.files[0].bytes, 2048);
  EXPECT_EQ(d.files[1].kind, "video");
  EXPECT_EQ(d.files[1].bytes, 5000000);

  EXPECT_EQ(rawQuery(path_, "SELECT channel || ' ' || level || ' ' || state || ' ' || value || ' ' || x_m || ' ' || "
                            "y_m || ' ' || time FROM alarms"),
            std::vector<std::string>{"CH4 alarm raised 812.5 3.25 -1.5 2026-11-22T08:30:15.550Z"});
  EXPECT_EQ(rawQuery(path_, "SELECT count(*) FROM events WHERE run_id IS NULL"), std::vector<std::string>{"1"});

  // A run without a summary.
  const auto bare = cat.run(cat.startRun(runOf("robot1", "bare", t0_)).id).value();
  EXPECT_FALSE(bare.summary);
  EXPECT_TRUE(bare.files.empty());
}

TEST_P(CatalogTest, ListRunsFilters) {
  auto cat = Catalog::open(path_);
  const auto a = cat.startRun(runOf("robot1", "Night round A", at("2026-11-20T22:00:00Z")));
  const auto b = cat.startRun(runOf("robot2", "night round B", at("2026-11-21T22:00:00Z")));
  const auto c = cat.startRun(runOf("robot1", "calibration", at("2026-11-22T08:00:00Z")));
  cat.endRun(a.id, "completed", at("2026-11-20T23:00:00Z"));
  cat.endRun(b.id, "failed", at("2026-11-21T22:10:00Z"));

  auto ids = [&](const RunFilter& f) {
    std::vector<std::string> out;
    for (const auto& r : cat.listRuns(f)) out.push_back(r.id);
    return out;
  };
  EXPECT_EQ(ids({}), (std::vector<std::string>{c.id, b.id, a.id}));  // newest first
  RunFilter f;
  f.robot = "robot1";
  EXPECT_EQ(ids(f), (std::vector<std::string>{c.id, a.id}));
  f = {};
  f.name_contains = "NIGHT";
  EXPECT_EQ(ids(f), (std::vector<std::string>{b.id, a.id}));
  f.outcome = "failed";
  EXPECT_EQ(ids(f), std::vector<std::string>{b.id});
  f = {};
  f.outcome = "running";
  EXPECT_EQ(ids(f), std::vector<std::string>{c.id});
  f = {};
  f.since = at("2026-11-21");
  EXPECT_EQ(ids(f), (std::vector<std::string>{c.id, b.id}));
  f.limit = 1;
  EXPECT_EQ(ids(f), std::vector<std::string>{c.id});
  f = {};
  f.outcome = "bogus";
  EXPECT_NE(errorOf([&] { cat.listRuns(f); }).find("unknown outcome 'bogus'"), std::string::npos);
}

TuningSession sessionOf(const std::string& id, const std::string& robot, Time created) {
  TuningSession s;
  s.id = id;
  s.created = created;
  s.robot = robot;
  s.reference = "circle r=3.5 m v=0.5 m/s laps=1";
  s.plant_json = R"({"left":{"gain":1,"time_constant_s":0.2},"right":{"gain":1,"time_constant_s":0.2}})";
  s.params = "kp,ki,kd,ke,kec,k1,k2,k3";
  s.algorithm = "GN_CRS2_LM + LN_BOBYQA";
  s.evals = 800;
  s.wall_s = 61.5;
  s.initial_cost = 12.25;
  s.best_cost = 7.125;
  s.initial_gains_json = R"({"kp":9.0})";
  s.best_gains_json = R"({"kp":13.5})";
  s.dir = "tuning/" + id;
  return s;
}

TEST_P(CatalogTest, TuningSessionsRoundTrip) {
  auto cat = Catalog::open(path_);
  cat.addTuningSession(sessionOf("tune-a", "robot1", t0_));
  auto b = sessionOf("tune-b", "", t0_ + milliseconds(60000));  // for no robot in particular
  b.cancelled = true;
  b.best_cost = std::nan("");  // cancelled before an evaluation finished
  cat.addTuningSession(b);
  cat.addTuningSession(sessionOf("tune-c", "robot2", t0_ - milliseconds(60000)));

  const auto all = cat.listTuningSessions();
  ASSERT_EQ(all.size(), 3u);
  EXPECT_EQ(all[0].id, "tune-b");  // newest first
  EXPECT_EQ(all[1].id, "tune-a");
  EXPECT_EQ(all[2].id, "tune-c");
  EXPECT_EQ(cat.listTuningSessions(1).size(), 1u);
  EXPECT_EQ(cat.listTuningSessions(0).size(), 3u);

  const auto a = cat.tuningSession("tune-a").value();
  const auto want = sessionOf("tune-a", "robot1", t0_);
  EXPECT_GT(a.rowid, 0);
  EXPECT_EQ(a.created, t0_);
  EXPECT_EQ(a.robot, "robot1");
  EXPECT_EQ(a.reference, want.reference);
  EXPECT_EQ(a.plant_json, want.plant_json);
  EXPECT_EQ(a.params, want.params);
  EXPECT_EQ(a.algorithm, want.algorithm);
  EXPECT_EQ(a.evals, 800);
  EXPECT_EQ(a.wall_s, 61.5);
  EXPECT_FALSE(a.cancelled);
  EXPECT_EQ(a.initial_cost, 12.25);
  EXPECT_EQ(a.best_cost, 7.125);
  EXPECT_EQ(a.initial_gains_json, want.initial_gains_json);
  EXPECT_EQ(a.best_gains_json, want.best_gains_json);
  EXPECT_EQ(a.dir, "tuning/tune-a");
  const auto rb = cat.tuningSession("tune-b").value();
  EXPECT_EQ(rb.robot, "");
  EXPECT_TRUE(rb.cancelled);
  EXPECT_TRUE(std::isnan(rb.best_cost));
  EXPECT_FALSE(cat.tuningSession("tune-z"));

  EXPECT_EQ(rawQuery(path_, "SELECT session_id || ' ' || created_time FROM tuning_sessions WHERE robot_id IS NULL"),
            std::vector<std::string>{"tune-b 2026-11-22T08:31:15.250Z"});
  EXPECT_EQ(rawQuery(path_, "SELECT count(*) FROM tuning_sessions WHERE best_cost IS NULL AND cancelled = 1"),
            std::vector<std::string>{"1"});

  EXPECT_EQ(errorOf([&] { cat.addTuningSession(sessionOf("tune-a", "robot1", t0_)); }),
            "catalog " + path_ + ": tuning session 'tune-a' is already recorded");
  EXPECT_EQ(errorOf([&] { cat.addTuningSession(sessionOf("", "robot1", t0_)); }),
            "catalog " + path_ + ": a tuning session needs an id");
  EXPECT_EQ(cat.listTuningSessions().size(), 3u);
}

TEST_P(CatalogTest, GainsPushesRoundTrip) {
  auto cat = Catalog::open(path_);
  cat.addTuningSession(sessionOf("tune-a", "robot1", t0_));
  const auto push = [](const std::string& robot, Time t, int64_t version, const std::string& status,
                       const std::string& reason, const std::string& session) {
    GainsPush p;
    p.robot = robot;
    p.time = t;
    p.version = version;
    p.gains_json = R"({"kp":13.5})";
    p.status = status;
    p.reason = reason;
    p.session_id = session;
    return p;
  };
  cat.addGainsPush(push("robot1", t0_ + milliseconds(1000), 2, "accepted", "", "tune-a"));
  cat.addGainsPush(push("robot1", t0_ + milliseconds(2000), 2, "rejected", "robot is tracking a path", ""));
  cat.addGainsPush(push("robot2", t0_ + milliseconds(1500), 7, "accepted", "", "from-another-pc"));

  const auto r1 = cat.listGainsPushes("robot1");
  ASSERT_EQ(r1.size(), 2u);
  EXPECT_EQ(r1[0].status, "rejected");  // newest first
  EXPECT_EQ(r1[0].reason, "robot is tracking a path");
  EXPECT_EQ(r1[0].session_id, "");
  EXPECT_EQ(r1[0].time, t0_ + milliseconds(2000));
  EXPECT_EQ(r1[1].status, "accepted");
  EXPECT_EQ(r1[1].version, 2);
  EXPECT_EQ(r1[1].session_id, "tune-a");
  EXPECT_EQ(r1[1].gains_json, R"({"kp":13.5})");
  EXPECT_GT(r1[0].rowid, r1[1].rowid);

  const auto all = cat.listGainsPushes("");
  ASSERT_EQ(all.size(), 3u);
  EXPECT_EQ(all[1].robot, "robot2");
  EXPECT_EQ(all[1].session_id, "from-another-pc");  // a session this catalog does not know is kept as given
  EXPECT_EQ(cat.listGainsPushes("", 1).size(), 1u);
  EXPECT_TRUE(cat.listGainsPushes("robot9").empty());
  EXPECT_EQ(rawQuery(path_, "SELECT count(*) FROM gains_pushes WHERE session_id IS NULL"),
            std::vector<std::string>{"1"});

  EXPECT_EQ(errorOf([&] { cat.addGainsPush(push("robot1", t0_, 3, "maybe", "", "")); }),
            "catalog " + path_ + ": unknown gains push status 'maybe' (accepted, rejected)");
  EXPECT_EQ(errorOf([&] { cat.addGainsPush(push("", t0_, 3, "accepted", "", "")); }),
            "catalog " + path_ + ": a gains push needs a robot id");
  EXPECT_EQ(cat.listGainsPushes("").size(), 3u);
}

TEST_P(CatalogTest, MarkIncompleteRunsEndsThemAtTheirLastRecord) {
  auto cat = Catalog::open(path_);
  const auto a = cat.startRun(runOf("robot1", "a", t0_));
  const auto b = cat.startRun(runOf("robot2", "b", t0_));
  const auto c = cat.startRun(runOf("robot3", "c", t0_));
  cat.endRun(c.id, "completed", t0_ + milliseconds(1000));
  cat.addEvent(a.id, "robot1", t0_ + milliseconds(4000), "tick", "");
  cat.addAlarm(a.id, "robot1", t0_ + milliseconds(7000), "CO", "warning", "raised", 30, 0, 0);

  EXPECT_EQ(cat.markIncompleteRuns(), (std::vector<std::string>{a.id, b.id}));
  EXPECT_TRUE(cat.markIncompleteRuns().empty());
  const auto da = cat.run(a.id).value().info;
  EXPECT_EQ(da.outcome, "incomplete");
  EXPECT_EQ(da.end.value(), t0_ + milliseconds(7000));
  EXPECT_EQ(cat.run(b.id).value().info.end.value(), t0_);
  EXPECT_EQ(cat.run(c.id).value().info.outcome, "completed");
}

// A server killed with SIGKILL in the middle of a run: every committed write is
// there, the file is sound, and the run is marked incomplete at the next start.
TEST_F(SqliteCatalogTest, SurvivesSigkillDuringARun) {
  constexpr int kAcksBeforeKill = 300;
  constexpr int kMaxEvents = 100000;  // bound if the kill never came
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {  // the "server": no gtest here, only _exit
    ::close(fds[0]);
    int code = 0;
    try {
      auto cat = Catalog::open(path_);
      const auto run = cat.startRun(runOf("robot1", "doomed", t0_));
      char id[64] = {};
      run.id.copy(id, sizeof id - 1);
      if (::write(fds[1], id, sizeof id) != sizeof id) ::_exit(3);
      for (int32_t i = 0; i < kMaxEvents; ++i) {
        cat.addEvent(run.id, "robot1", t0_ + milliseconds(i), "tick", std::to_string(i));
        if (::write(fds[1], &i, sizeof i) != sizeof i) ::_exit(3);  // acknowledged = committed
      }
    } catch (...) {
      code = 2;
    }
    ::_exit(code);
  }
  ::close(fds[1]);
  auto readAll = [&](void* buf, std::size_t n) {
    auto* p = static_cast<char*>(buf);
    while (n > 0) {
      const ssize_t got = ::read(fds[0], p, n);
      if (got <= 0) return false;
      p += got;
      n -= static_cast<std::size_t>(got);
    }
    return true;
  };
  char id[64] = {};
  const bool started = readAll(id, sizeof id);
  int32_t last_ack = -1, ack = 0;
  while (started && last_ack + 1 < kAcksBeforeKill && readAll(&ack, sizeof ack)) last_ack = ack;
  ::kill(pid, SIGKILL);
  while (readAll(&ack, sizeof ack)) last_ack = ack;  // acknowledged before the kill landed
  ::close(fds[0]);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(started);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "child status " << status;
  ASSERT_GE(last_ack + 1, kAcksBeforeKill);
  EXPECT_TRUE(fs::exists(path_ + "-wal"));  // killed with its WAL not checkpointed

  auto cat = Catalog::open(path_);
  EXPECT_EQ(cat.integrityCheck(), "ok");
  EXPECT_EQ(cat.markIncompleteRuns(), std::vector<std::string>{id});
  const auto d = cat.run(id).value();
  EXPECT_EQ(d.info.outcome, "incomplete");
  // Every acknowledged event, and at most the one in flight.
  EXPECT_GE(d.event_count, last_ack + 1);
  EXPECT_LE(d.event_count, last_ack + 2);
  EXPECT_EQ(rawQuery(path_, "SELECT count(DISTINCT text) = count(*) AND min(CAST(text AS INTEGER)) = 0 AND "
                            "max(CAST(text AS INTEGER)) = count(*) - 1 FROM events"),
            std::vector<std::string>{"1"});
  EXPECT_GE(d.info.end.value(), t0_ + milliseconds(last_ack));
}

TEST_F(SqliteCatalogTest, ReadableWithTheSqlite3Shell) {
  if (!fs::exists("/usr/bin/sqlite3")) GTEST_SKIP() << "no /usr/bin/sqlite3 (Debian sqlite3)";
  {
    auto cat = Catalog::open(path_);
    const auto r = cat.startRun(runOf("robot1", "a", t0_));
    cat.startRun(runOf("robot1", "b", t0_));
    Summary s;
    s.gas = {{"CH4", "ppm", 812.5, 120.25}};
    cat.setSummary(r.id, s);
  }
  const std::string cmd = "/usr/bin/sqlite3 '" + path_ +
                          "' 'PRAGMA integrity_check; SELECT count(*) FROM runs;"
                          " SELECT channel, max, mean FROM run_gas; SELECT outcome FROM run_overview LIMIT 1;' 2>&1";
  std::FILE* p = ::popen(cmd.c_str(), "r");
  ASSERT_TRUE(p);
  std::string out;
  char buf[256];
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  EXPECT_EQ(::pclose(p), 0) << out;
  EXPECT_EQ(out, "ok\n2\nCH4|812.5|120.25\nrunning\n");
}

TEST_F(SqliteCatalogTest, BadFilesGiveErrorsNamingThePath) {
  const std::string missing = (dir_ / "no_such_dir" / "catalog.sqlite").string();
  const std::string e1 = errorOf([&] { Catalog::open(missing); });
  EXPECT_NE(e1.find(missing), std::string::npos) << e1;
  EXPECT_NE(e1.find("unable to open"), std::string::npos) << e1;

  const std::string text = (dir_ / "notes.txt").string();
  std::ofstream(text) << std::string(2000, 'x');
  const std::string e2 = errorOf([&] { Catalog::open(text); });
  EXPECT_NE(e2.find(text), std::string::npos) << e2;
  EXPECT_NE(e2.find("not a database"), std::string::npos) << e2;

  const std::string foreign = (dir_ / "other.sqlite").string();
  {
    sqlite3* db = nullptr;
    sqlite3_open(foreign.c_str(), &db);
    sqlite3_exec(db, "CREATE TABLE t (x)", nullptr, nullptr, nullptr);
    sqlite3_close(db);
  }
  const std::string e3 = errorOf([&] { Catalog::open(foreign); });
  EXPECT_NE(e3.find(foreign), std::string::npos) << e3;
  EXPECT_NE(e3.find("not a run catalog"), std::string::npos) << e3;
  EXPECT_EQ(rawQuery(foreign, "SELECT count(*) FROM sqlite_master"), std::vector<std::string>{"1"});  // untouched
  EXPECT_EQ(rawQuery(foreign, "PRAGMA journal_mode"), std::vector<std::string>{"delete"});
}

TEST_P(CatalogTest, ConcurrentWritersShareOneCatalog) {
  auto cat = Catalog::open(path_);
  const auto r = cat.startRun(runOf("robot1", "busy", t0_));
  constexpr int kThreads = 4, kEach = 100;
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      for (int i = 0; i < kEach; ++i) {
        if (i % 2)
          cat.addEvent(r.id, "robot1", t0_ + milliseconds(i), "tick", std::to_string(t));
        else
          cat.addAlarm(r.id, "robot1", t0_ + milliseconds(i), "CO", "warning", "raised", i, 0, 0);
        if (i % 25 == 0) cat.listRuns();
      }
    });
  for (auto& th : threads) th.join();
  const auto d = cat.run(r.id).value();
  EXPECT_EQ(d.event_count + d.alarm_count, kThreads * kEach);
  EXPECT_EQ(cat.integrityCheck(), "ok");
}

TEST_P(CatalogTest, ServersKeepTheirOwnRunsAndSayWhereEachRobotIs) {
  // Two servers writing into one catalog (one file, or one database).
  auto a = Catalog::open(path_);
  auto b = Catalog::open(path_);
  a.setServerId("ops-a");
  b.setServerId("ops-b");
  const auto ra = a.startRun(runOf("robot1", "a", t0_));
  const auto rb = b.startRun(runOf("robot2", "b", t0_));
  EXPECT_EQ(ra.server, "ops-a");
  a.addEvent(ra.id, "robot1", t0_ + milliseconds(10), "note", "x");
  b.addAlarm(rb.id, "robot2", t0_ + milliseconds(20), "H2S", "alarm", "raised", 15, 1, 2);
  EXPECT_EQ(rawQuery(path_, "SELECT server_id FROM alarms"), std::vector<std::string>{"ops-b"});
  EXPECT_EQ(rawQuery(path_, "SELECT server_id FROM events"), std::vector<std::string>{"ops-a"});
  RunFilter f;
  f.server = "ops-b";
  const auto only_b = a.listRuns(f);
  ASSERT_EQ(only_b.size(), 1u);
  EXPECT_EQ(only_b[0].id, rb.id);
  EXPECT_EQ(only_b[0].server, "ops-b");
  // A restarted ops-a ends its own open run, never ops-b's running one.
  EXPECT_EQ(a.markIncompleteRuns(), std::vector<std::string>{ra.id});
  EXPECT_EQ(b.run(rb.id).value().info.outcome, "");
  EXPECT_EQ(b.run(ra.id).value().info.outcome, "incomplete");

  a.upsertServer({"ops-a", "ops-a:7600", "/srv/runs", "0.9.0", t0_, t0_ + milliseconds(1000)});
  b.upsertServer({"ops-b", "ops-b:7600", "/srv/runs", "0.9.0", t0_, t0_ + milliseconds(2000)});
  a.upsertServer({"ops-a", "ops-a:7601", "/srv/runs", "0.9.1", t0_, t0_ + milliseconds(3000)});
  const auto servers = b.listServers();
  ASSERT_EQ(servers.size(), 2u);
  EXPECT_EQ(servers[0].id, "ops-a");  // seen most recently
  EXPECT_EQ(servers[0].attach, "ops-a:7601");
  EXPECT_EQ(servers[0].software_version, "0.9.1");
  EXPECT_EQ(servers[0].seen, t0_ + milliseconds(3000));

  b.setPresence({"robot2", "ops-b", true, "TELEOP", 1.5, -2.25, t0_});
  a.setPresence({"robot1", "ops-a", false, "", std::nullopt, std::nullopt, t0_});
  a.setPresence({"robot2", "ops-a", true, "AUTO", 3.0, 4.0, t0_ + milliseconds(500)});  // robot2 moved to ops-a
  const auto where = b.listPresence();
  ASSERT_EQ(where.size(), 2u);
  EXPECT_EQ(where[0].robot, "robot1");
  EXPECT_FALSE(where[0].online);
  EXPECT_FALSE(where[0].x_m);
  EXPECT_EQ(where[1].server, "ops-a");
  EXPECT_EQ(where[1].mode, "AUTO");
  EXPECT_EQ(where[1].x_m, 3.0);
  EXPECT_EQ(where[1].seen, t0_ + milliseconds(500));
  EXPECT_FALSE(errorOf([&] { a.setPresence({"robot3", "", true, "", {}, {}, t0_}); }).empty());
}

INSTANTIATE_TEST_SUITE_P(Engines, CatalogTest, ::testing::Values(Engine::kSqlite, Engine::kPostgres),
                         [](const auto& info) { return info.param == Engine::kSqlite ? "sqlite" : "postgresql"; });

TEST_F(PostgresCatalogTest, TwoServersShareOneDatabase) {
  // Two connections as two pc_servers would hold: the schema is migrated once,
  // run ids stay unique across them, each sees the other's writes at once.
  auto a = Catalog::open(path_);
  auto b = Catalog::open(path_);
  EXPECT_EQ(b.schemaVersion(), static_cast<int>(schemaMigrations().size()));
  const auto ra = a.startRun(runOf("robot1", "a", t0_));
  const auto rb = b.startRun(runOf("robot1", "b", t0_));
  EXPECT_EQ(ra.id, "20261122-083015-robot1");
  EXPECT_EQ(rb.id, "20261122-083015-robot1-2");
  b.addAlarm(ra.id, "robot1", t0_ + milliseconds(5), "H2S", "alarm", "raised", 12.5, 1.0, 2.0);
  EXPECT_EQ(a.run(ra.id).value().alarm_count, 1);
  EXPECT_EQ(a.listRuns().size(), 2u);
  EXPECT_EQ(rawQuery(path_, "SELECT value FROM catalog_meta WHERE key = 'schema_version'"),
            std::vector<std::string>{std::to_string(schemaMigrations().size())});
}

TEST_F(PostgresCatalogTest, RefusesANewerSchemaAndAForeignDatabase) {
  { auto cat = Catalog::open(path_); }
  rawQuery(path_, "UPDATE catalog_meta SET value = '999' WHERE key = 'schema_version'");
  EXPECT_NE(errorOf([&] { Catalog::open(path_); }).find("schema version 999 was written by a newer program"),
            std::string::npos);
  const std::string foreign = inspect::test::freshPostgresDatabase("foreign");
  rawQuery(foreign, "CREATE TABLE t (x int)");
  EXPECT_EQ(errorOf([&] { Catalog::open(foreign); }),
            "catalog " + foreign + ": not a run catalog (has tables but no catalog_meta)");
  EXPECT_EQ(rawQuery(foreign, "SELECT count(*) FROM information_schema.tables WHERE table_schema = 'public'"),
            std::vector<std::string>{"1"});  // untouched
}

TEST_F(PostgresCatalogTest, AnUnreachableServerIsNamedWithoutItsPassword) {
  const std::string url = "postgresql://inspect:s3cret@127.0.0.1:1/fleet?connect_timeout=2";
  const std::string e = errorOf([&] { Catalog::open(url); });
  EXPECT_EQ(e.rfind("catalog postgresql://inspect@127.0.0.1:1/fleet?connect_timeout=2: cannot connect: ", 0), 0u) << e;
  EXPECT_EQ(e.find("s3cret"), std::string::npos) << e;
  EXPECT_EQ(redactUrl("postgres://u:p@h/db?sslmode=require&password=x&a=b"),
            "postgres://u@h/db?sslmode=require&password=***&a=b");
  EXPECT_EQ(postgresParams("SELECT ?, ?, '?' WHERE a = ?2"), "SELECT $1, $2, '?' WHERE a = $2");
  EXPECT_EQ(postgresDdl("id INTEGER PRIMARY KEY, n INTEGER NOT NULL, x REAL"),
            "id BIGINT GENERATED BY DEFAULT AS IDENTITY PRIMARY KEY, n BIGINT NOT NULL, x DOUBLE PRECISION");
}

TEST(CatalogTime, FormatsAndParsesIsoUtc) {
  const Time t = parseIsoUtc("2026-11-22T08:30:15.123Z").value();
  EXPECT_EQ(formatIsoUtc(t), "2026-11-22T08:30:15.123Z");
  EXPECT_EQ(std::chrono::system_clock::to_time_t(t), 1795336215);
  EXPECT_EQ(parseIsoUtc("2026-11-22").value(), parseIsoUtc("2026-11-22T00:00:00Z").value());
  EXPECT_EQ(parseIsoUtc("2026-11-22 08:30").value(), parseIsoUtc("2026-11-22T08:30:00.000").value());
  for (const char* bad : {"", "2026-11", "2026-13-01", "2026-02-30", "2026-11-22T25:00", "2026-11-22T08:30:15.",
                          "2026-11-22x", "20261122"})
    EXPECT_FALSE(parseIsoUtc(bad)) << bad;
}

}  // namespace
