// A fleet on one PostgreSQL catalog through the real programs: two
// pc_servers (ops-a, ops-b), a simulated robot each, one database (a server
// of this test's own, tests/support/pg_cluster.sh). The database is stopped
// for 20 s in the middle of ops-a's recorded run and started again: ops-a
// goes on recording and says so, writes everything through when it is back,
// and the catalog then holds each event of the run exactly once (as many as
// the run's MCAP file, read by @mcap/core, has). An operator on either server
// sees both robots (`robots --fleet`) and both runs (`runs --fleet`), and
// both runs are copied to the fleet's shared runs root.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <string>
#include <thread>

#include "tests/support/postgres_server.hpp"
#include "tests/support/sql_query.hpp"
#include "tests/support/stack.hpp"

using namespace inspect::test;

namespace {


std::string runIdIn(const std::string& runs, const std::string& robot) {
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(runs, ec))
    if (e.is_directory() && e.path().filename().string().find("-" + robot) != std::string::npos)
      return e.path().filename().string();
  return "";
}

std::string one(const std::vector<std::string>& rows) { return rows.empty() ? "(none)" : rows[0]; }

}  // namespace

TEST(FleetStack, TwoServersShareOneCatalogAndADatabaseOutageLosesNothing) {
  const char* reader = std::getenv("INSPECT_MCAP_READER");
  ASSERT_NE(reader, nullptr) << "INSPECT_MCAP_READER: the @mcap/core reader (ctest fixture mcap_reader)";
  OwnPostgres pg;
  ASSERT_TRUE(postgresQuery(pg.url(), "CREATE DATABASE fleet").empty());
  const std::string url = pg.url("fleet");

  // ops-a records a run through the outage in the gas lab: the run starts
  // before it; the CH4 alarm by valve_A (x 6 m), e-stop, resume and the
  // run's end fall in it; the fleet is listed after.
  Stack a("fleet-a");
  const std::string runs_a = a.dir() / "runs";
  const std::string shared = a.dir() / "shared";  // the fleet's shared runs root
  ASSERT_TRUE(a.startServer("expect robots >= 1 within 20\n"
                            "record start south aisle\n"
                            "drive 0.35 0\n"
                            "wait 15\n"
                            "estop\n"
                            "wait 1\n"
                            "resume\n"
                            "stop\n"
                            "record stop\n"
                            "wait 16\n"
                            "robots --fleet\n"
                            "runs --fleet\n",
                            {"--runs-dir", runs_a, "--catalog", url, "--server-id", "ops-a", "--shared-runs", shared}))
      << a.logs();
  // ops-b records a short run before the outage and lists the fleet after it.
  Stack b("fleet-b");
  const std::string runs_b = b.dir() / "runs";
  ASSERT_TRUE(b.startServer("expect robots >= 1 within 20\n"
                            "record start south wing\n"
                            "wait 1\n"
                            "record stop\n"
                            "wait 32\n"
                            "robots --fleet\n"
                            "runs --fleet\n",
                            {"--runs-dir", runs_b, "--catalog", url, "--server-id", "ops-b", "--shared-runs", shared}))
      << b.logs();
  a.startRobot("robot1", "gas_lab.yaml");
  b.startRobot("robot2");

  // The database goes away 2 s into ops-a's run, for 20 s.
  ASSERT_TRUE(waitUntil([&] { return !runIdIn(runs_a, "robot1").empty(); }, 40.0)) << a.logs();
  std::this_thread::sleep_for(std::chrono::seconds(2));
  pg.halt();
  const auto halted = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(std::chrono::seconds(20));
  pg.resume();
  const double outage_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - halted).count();

  ASSERT_TRUE(a.server().wait(60.0).has_value()) << a.logs();
  ASSERT_TRUE(b.server().wait(60.0).has_value()) << b.logs();
  const std::string out_a = a.serverOutput(), out_b = b.serverOutput();
  const std::string run_a = runIdIn(runs_a, "robot1"), run_b = runIdIn(runs_b, "robot2");
  ASSERT_FALSE(run_b.empty()) << b.logs();

  // 1. ops-a said the catalog went away and came back, with the figures.
  EXPECT_NE(out_a.find("recording goes on, the catalog's writes kept in"), std::string::npos) << out_a;
  std::smatch m;
  const std::regex back(R"(back after ([0-9.]+) s away; ([0-9]+) writes kept meanwhile written through in ([0-9.]+) s)");
  ASSERT_TRUE(std::regex_search(out_a, m, back)) << out_a;
  const int backlog = std::stoi(m[2]);
  EXPECT_GE(backlog, 8) << out_a;  // the alarm, e-stop, resume, the run's end, summary, files
  RecordProperty("outage_s", std::to_string(outage_s));
  RecordProperty("backlog_writes", backlog);
  RecordProperty("catch_up_s", m[3].str());
  std::printf("outage %.1f s; ops-a kept %d writes, written through in %s s after %s s away\n", outage_s, backlog,
              m[3].str().c_str(), m[1].str().c_str());

  // 2. Either operator sees both robots and both runs, and where to attach.
  if (const auto at = out_b.find("robot            state"); at != std::string::npos)
    std::printf("ops-b's console, robots --fleet and runs --fleet:\n%s\n", out_b.substr(at).c_str());
  for (const std::string* out : {&out_a, &out_b}) {
    EXPECT_NE(out->find("robot1 "), std::string::npos) << *out;
    EXPECT_NE(out->find("robot2 "), std::string::npos) << *out;
    EXPECT_NE(out->find(run_a), std::string::npos) << *out;
    EXPECT_NE(out->find(run_b), std::string::npos) << *out;
    EXPECT_NE(out->find("ops-a @"), std::string::npos) << *out;
    EXPECT_NE(out->find("ops-b @"), std::string::npos) << *out;
  }
  EXPECT_NE(out_b.find("robot2           online"), std::string::npos) << out_b;

  // 3. The catalog has ops-a's run whole and once: its events are those of
  // its MCAP file (the robot's and the server's), none lost, none doubled.
  EXPECT_EQ(one(rawQuery(url, "SELECT outcome FROM runs WHERE run_id = '" + run_a + "'")), "stopped");
  EXPECT_EQ(one(rawQuery(url, "SELECT server_id FROM runs WHERE run_id = '" + run_a + "'")), "ops-a");
  EXPECT_EQ(one(rawQuery(url, "SELECT server_id FROM runs WHERE run_id = '" + run_b + "'")), "ops-b");
  const auto counts = captureOutput(std::string("node ") + reader + " " + runs_a + "/" + run_a + "/run.mcap");
  const int mcap_events =
      std::max(mcapTopicCount(counts, "/robot1/events"), 0) + std::max(mcapTopicCount(counts, "/robot1/server_events"), 0);
  const int catalog_events =
      std::stoi(one(rawQuery(url, "SELECT count(*) FROM events WHERE run_id = '" + run_a + "'")));
  EXPECT_EQ(catalog_events, mcap_events) << counts;
  EXPECT_EQ(one(rawQuery(url, "SELECT count(*) FROM (SELECT time, kind, text FROM events WHERE run_id = '" + run_a +
                                  "' GROUP BY time, kind, text HAVING count(*) > 1) AS d")),
            "0");
  EXPECT_EQ(one(rawQuery(url, "SELECT count(*) FROM run_summary WHERE run_id = '" + run_a + "'")), "1");
  EXPECT_GE(std::stoi(one(rawQuery(url, "SELECT count(*) FROM alarms WHERE run_id = '" + run_a + "'"))), 1)
      << "no gas alarm in the run: " << out_a;
  EXPECT_EQ(one(rawQuery(url, "SELECT count(*) FROM runs")), "2");
  EXPECT_EQ(one(rawQuery(runs_a + "/catalog-spool.sqlite", "SELECT count(*) FROM writes")), "0");
  // Both runs are in the shared runs root, for either server's report, export and replay.
  EXPECT_TRUE(std::filesystem::exists(shared + "/ops-a/" + run_a + "/run.mcap"));
  EXPECT_TRUE(std::filesystem::exists(shared + "/ops-b/" + run_b + "/run.mcap"));
  EXPECT_EQ(one(rawQuery(url, "SELECT count(*) FROM run_files WHERE kind = 'shared'")), "2");
  const std::string rows_a = one(rawQuery(url, "SELECT (SELECT count(*) FROM events WHERE server_id = 'ops-a') || ' events, ' ||"
                                               " (SELECT count(*) FROM alarms WHERE server_id = 'ops-a') || ' alarms'"));
  RecordProperty("catalog_rows_ops_a", rows_a);
  std::printf("catalog: ops-a %s; run %s: %d events in the catalog, %d in its MCAP\n", rows_a.c_str(), run_a.c_str(),
              catalog_events, mcap_events);
}
