// The catalog's local spool (CatalogSpool) on real databases: writes go
// through in order and the spool empties; a write the catalog already has
// (a crash between its commit and the spool's delete) is not written twice;
// a refused write is dropped and said while the others go through; and a
// PostgreSQL server of the test's own stopped mid-run (and the recording
// server restarted meanwhile): every write kept, written through in order
// when it is back, the catalog then equal to a SQLite catalog fed the same.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <thread>

#include "shared/catalog/catalog.hpp"
#include "shared/catalog/catalog_spool.hpp"
#include "tests/support/postgres_server.hpp"
#include "tests/support/sql_query.hpp"

using namespace inspect::catalog;
namespace fs = std::filesystem;
using inspect::test::rawQuery;
using std::chrono::milliseconds;

namespace {

constexpr milliseconds kFlush{10000};

class CatalogSpoolTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    dir_ = fs::temp_directory_path() / ("catalog_spool_test_" + std::to_string(::getpid()) + "_" + name);
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string file(const char* name) const { return (dir_ / name).string(); }

  fs::path dir_;
  const Time t0_ = parseIsoUtc("2026-12-06T08:30:15.250Z").value();
};

RunStart spooledRun(const std::string& id, const std::string& robot, Time start) {
  RunStart r;
  r.id = id;
  r.robot = robot;
  r.name = "night round";
  r.route = "routes/corridor.yaml";
  r.software_version = "0.1.0";
  r.dir = "runs";
  r.start = start;
  return r;
}

// A run's writes as the recorder makes them: start, events, an alarm, summary, files, end.
void writeRun(CatalogSpool& s, const std::string& id, Time t0, int events) {
  s.startRun(spooledRun(id, "robot1", t0));
  for (int i = 0; i < events; ++i)
    s.addEvent(id, "robot1", t0 + milliseconds(100 * (i + 1)), "INFO", "waypoint " + std::to_string(i));
  s.addAlarm(id, "robot1", t0 + milliseconds(50), "H2S", "HIGH", "raised", 12.5, 3.7, 3.85);
  Summary sum;
  sum.duration_s = 42.5;
  sum.distance_m = 12.25;
  sum.min_person_m = 0.8;
  sum.gas.push_back({"H2S", "ppm", 12.5, 3.25});
  s.setSummary(id, sum);
  s.addFile(id, "mcap", "runs/" + id + "/run.mcap", 1234);
  s.endRun(id, "completed", t0 + milliseconds(100 * (events + 1)));
}

// What a catalog holds, one text line per row, comparable across engines.
std::vector<std::string> contents(const std::string& where) {
  std::vector<std::string> out;
  for (const char* sql :
       {"SELECT run_id || '|' || robot_id || '|' || name || '|' || start_time || '|' || COALESCE(end_time, '-')"
        " || '|' || COALESCE(outcome, '-') FROM runs ORDER BY run_id",
        "SELECT run_id || '|' || time || '|' || kind || '|' || text FROM events ORDER BY time, text",
        "SELECT run_id || '|' || time || '|' || channel || '|' || state || '|' || CAST(value AS TEXT) FROM alarms"
        " ORDER BY time",
        "SELECT run_id || '|' || CAST(duration_s AS TEXT) || '|' || CAST(distance_m AS TEXT) FROM run_summary"
        " ORDER BY run_id",
        "SELECT run_id || '|' || kind || '|' || path || '|' || CAST(bytes AS TEXT) FROM run_files ORDER BY run_id, path"})
    for (auto& row : rawQuery(where, sql)) out.push_back(std::move(row));
  return out;
}

int64_t count(const std::string& where, const std::string& table) {
  const auto rows = rawQuery(where, "SELECT count(*) FROM " + table);
  return rows.empty() ? -1 : std::stoll(rows[0]);
}

bool anyNotice(const std::vector<std::string>& notices, const std::string& part) {
  for (const auto& n : notices)
    if (n.find(part) != std::string::npos) return true;
  return false;
}

}  // namespace

TEST_F(CatalogSpoolTest, WritesGoThroughInOrderAndTheSpoolEmpties) {
  auto cat = Catalog::open(file("catalog.sqlite"));
  {
    CatalogSpool spool(cat, file("spool.sqlite"));
    writeRun(spool, "20261206-083015-robot1", t0_, 3);
    ASSERT_TRUE(spool.flush(kFlush));
    const auto st = spool.status();
    EXPECT_TRUE(st.reachable);
    EXPECT_EQ(st.pending, 0);
    EXPECT_EQ(st.written, 8);
    EXPECT_EQ(st.dropped, 0);
  }
  const auto d = cat.run("20261206-083015-robot1");
  ASSERT_TRUE(d);
  EXPECT_EQ(d->info.outcome, "completed");
  EXPECT_EQ(d->info.start, t0_);
  EXPECT_EQ(d->event_count, 3);
  EXPECT_EQ(d->alarm_count, 1);
  ASSERT_TRUE(d->summary);
  EXPECT_DOUBLE_EQ(d->summary->distance_m, 12.25);
  EXPECT_EQ(d->summary->min_person_m, 0.8);
  ASSERT_EQ(d->summary->gas.size(), 1u);
  EXPECT_DOUBLE_EQ(d->summary->gas[0].mean, 3.25);
  ASSERT_EQ(d->files.size(), 1u);
  EXPECT_EQ(d->files[0].bytes, 1234);
  EXPECT_EQ(count(file("spool.sqlite"), "writes"), 0);
}

TEST_F(CatalogSpoolTest, AWriteTheCatalogAlreadyHasIsNotWrittenTwice) {
  // The catalog committed, then the server died before the spool forgot the
  // writes: they are in the spool again at the next start.
  auto cat = Catalog::open(file("catalog.sqlite"));
  std::string spool_id;
  {
    CatalogSpool spool(cat, file("spool.sqlite"));
    spool_id = spool.id();
    spool.startRun(spooledRun("r1", "robot1", t0_));
    spool.addEvent("r1", "robot1", t0_, "INFO", "one");
    spool.addEvent("r1", "robot1", t0_, "INFO", "two");
    ASSERT_TRUE(spool.flush(kFlush));
  }
  EXPECT_EQ(cat.spoolApplied(spool_id), 3);
  const auto again = rawQuery(file("spool.sqlite"),
                              "INSERT INTO writes (seq, op, queued_unix) VALUES"
                              " (2, '{\"op\":\"event\",\"run\":\"r1\",\"robot\":\"robot1\",\"t\":0,\"kind\":\"INFO\","
                              "\"text\":\"one\"}', 0),"
                              " (3, '{\"op\":\"event\",\"run\":\"r1\",\"robot\":\"robot1\",\"t\":0,\"kind\":\"INFO\","
                              "\"text\":\"two\"}', 0) RETURNING seq");
  ASSERT_EQ(again.size(), 2u);
  {
    CatalogSpool spool(cat, file("spool.sqlite"));
    EXPECT_EQ(spool.id(), spool_id);
    ASSERT_TRUE(spool.flush(kFlush));  // (the writer may have taken them already: no count before)
    EXPECT_EQ(spool.status().written, 0);  // both skipped
    spool.addEvent("r1", "robot1", t0_, "INFO", "three");  // seq 4: never a used one
    ASSERT_TRUE(spool.flush(kFlush));
    EXPECT_EQ(spool.status().written, 1);
  }
  EXPECT_EQ(cat.run("r1")->event_count, 3);
  EXPECT_EQ(cat.spoolApplied(spool_id), 4);
}

TEST_F(CatalogSpoolTest, ARefusedWriteIsDroppedAndSaidWhileTheOthersGoThrough) {
  auto cat = Catalog::open(file("catalog.sqlite"));
  CatalogSpool spool(cat, file("spool.sqlite"));
  spool.startRun(spooledRun("r1", "robot1", t0_));
  spool.endRun("no-such-run", "completed", t0_);
  spool.addEvent("r1", "robot1", t0_, "INFO", "after the refused one");
  spool.endRun("r1", "completed", t0_ + milliseconds(500));
  ASSERT_TRUE(spool.flush(kFlush));
  const auto st = spool.status();
  EXPECT_EQ(st.dropped, 1);
  EXPECT_EQ(st.written, 3);
  EXPECT_EQ(st.pending, 0);
  uint64_t cursor = 0;
  const auto notices = spool.noticesSince(cursor);
  ASSERT_EQ(notices.size(), 1u);
  EXPECT_NE(notices[0].find("refused and is dropped"), std::string::npos) << notices[0];
  EXPECT_NE(notices[0].find("no run 'no-such-run'"), std::string::npos) << notices[0];
  EXPECT_TRUE(spool.noticesSince(cursor).empty());
  EXPECT_EQ(cat.run("r1")->event_count, 1);
  EXPECT_EQ(cat.run("r1")->info.outcome, "completed");
}

TEST_F(CatalogSpoolTest, AStartWrittenAgainIsTheSameRunAndATakenIdIsRefused) {
  auto cat = Catalog::open(file("catalog.sqlite"));
  cat.setServerId("ops-a");
  const auto a = cat.startRun(spooledRun("r1", "robot1", t0_));
  const auto again = cat.startRun(spooledRun("r1", "robot1", t0_));
  EXPECT_EQ(again.rowid, a.rowid);
  EXPECT_EQ(cat.listRuns().size(), 1u);
  try {
    cat.startRun(spooledRun("r1", "robot1", t0_ + milliseconds(2000)));
    FAIL() << "a taken id was accepted";
  } catch (const CatalogError& e) {
    EXPECT_NE(std::string(e.what()).find("run id 'r1' is taken by another run (server ops-a)"), std::string::npos)
        << e.what();
  }
}

TEST_F(CatalogSpoolTest, APostgresOutageKeepsEveryWriteAndWritesThemThroughInOrder) {
  inspect::test::OwnPostgres pg;
  ASSERT_TRUE(inspect::test::postgresQuery(pg.url(), "CREATE DATABASE fleet").empty());
  const std::string url = pg.url("fleet");
  auto cat = Catalog::open(url);
  cat.setServerId("ops-a");
  auto reference = Catalog::open(file("reference.sqlite"));  // the same writes on SQLite
  reference.setServerId("ops-a");
  CatalogSpool ref(reference, file("reference-spool.sqlite"));

  auto spool = std::make_unique<CatalogSpool>(cat, file("spool.sqlite"));
  const std::string id = "20261206-083015-robot1";
  for (CatalogSpool* s : {spool.get(), &ref}) {
    s->startRun(spooledRun(id, "robot1", t0_));
    s->addEvent(id, "robot1", t0_ + milliseconds(10), "INFO", "before the outage");
  }
  ASSERT_TRUE(spool->flush(kFlush));

  pg.halt();
  for (CatalogSpool* s : {spool.get(), &ref})
    for (int i = 0; i < 20; ++i) s->addEvent(id, "robot1", t0_ + milliseconds(100 * (i + 1)), "INFO", "during " + std::to_string(i));
  EXPECT_FALSE(spool->flush(milliseconds(300)));
  auto st = spool->status();
  EXPECT_FALSE(st.reachable);
  EXPECT_EQ(st.pending, 20);
  EXPECT_NE(st.error.find("catalog " + url), std::string::npos) << st.error;
  uint64_t cursor = 0;
  auto notices = spool->noticesSince(cursor);
  EXPECT_TRUE(anyNotice(notices, "recording goes on")) << (notices.empty() ? "" : notices[0]);

  // The recording server restarts during the outage: the spool file keeps the writes.
  spool.reset();
  spool = std::make_unique<CatalogSpool>(cat, file("spool.sqlite"));
  for (CatalogSpool* s : {spool.get(), &ref}) {
    s->addAlarm(id, "robot1", t0_ + milliseconds(2500), "H2S", "HIGH", "raised", 12.5, 3.7, 3.85);
    s->endRun(id, "completed", t0_ + milliseconds(3000));
  }
  EXPECT_FALSE(spool->flush(milliseconds(300)));
  EXPECT_EQ(spool->status().pending, 22);

  pg.resume();
  ASSERT_TRUE(spool->flush(kFlush));
  ASSERT_TRUE(ref.flush(kFlush));
  st = spool->status();
  EXPECT_TRUE(st.reachable);
  EXPECT_EQ(st.pending, 0);
  EXPECT_EQ(st.dropped, 0);
  EXPECT_EQ(st.last_backlog, 22);
  cursor = 0;
  notices = spool->noticesSince(cursor);
  EXPECT_TRUE(anyNotice(notices, "22 writes kept meanwhile written through in"))
      << (notices.empty() ? "" : notices.back());
  RecordProperty("backlog_writes", static_cast<int>(st.last_backlog));
  RecordProperty("catch_up_ms", static_cast<int>(st.last_catch_up_s * 1000));

  const auto pg_rows = contents(url), sqlite_rows = contents(file("reference.sqlite"));
  EXPECT_EQ(pg_rows, sqlite_rows);
  EXPECT_EQ(count(url, "events"), 21);
  EXPECT_EQ(count(url, "alarms"), 1);
  EXPECT_EQ(cat.run(id)->info.outcome, "completed");
}
