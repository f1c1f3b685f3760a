// bench_catalog: what the run catalog's writes cost the recording thread,
// directly and through the local spool (CatalogSpool), on SQLite and on a
// PostgreSQL server of its own (tests/support/pg_cluster.sh, Unix socket);
// and how long a spool takes to catch up after the database was away.
//
//   bench_catalog [--writes N] [--json FILE] [--quick]
//
// Each case writes N events of one run. "direct" is Catalog::addEvent on the
// calling thread (what the recorder did before the spool); "spool" is
// CatalogSpool::addEvent (a row in the local spool file; the writer thread
// writes it through). "vs direct" divides by the same engine's direct cost,
// measured in the same run. The outage case stops PostgreSQL, queues N
// writes, starts it again and times the write-through.
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "shared/catalog/catalog.hpp"
#include "shared/catalog/catalog_spool.hpp"
#include "shared/util/cli_args.hpp"
#include "tests/support/postgres_server.hpp"

namespace fs = std::filesystem;
using namespace inspect;
using namespace inspect::catalog;
using Clock = std::chrono::steady_clock;
using Json = nlohmann::json;

namespace {

struct Case {
  std::string name, engine;
  int writes = 0;
  double us_per_write = 0;      // on the calling thread
  double vs_direct = 0;         // the same engine's direct cost = 1
  double through_s = 0;         // until every write was in the catalog
  double writes_per_s = 0;      // written through per second
};

double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

RunStart runOf(const std::string& id) {
  RunStart r;
  r.id = id;
  r.robot = "robot1";
  r.name = "bench";
  r.start = std::chrono::system_clock::now();
  return r;
}

Case direct(Catalog& cat, const std::string& engine, int n) {
  const std::string id = "direct-" + engine;
  cat.startRun(runOf(id));
  const auto t0 = Clock::now();
  for (int i = 0; i < n; ++i)
    cat.addEvent(id, "robot1", std::chrono::system_clock::now(), "INFO", "waypoint " + std::to_string(i));
  const double s = secondsSince(t0);
  return {"direct " + engine, engine, n, s / n * 1e6, 1.0, s, n / s};
}

Case spooled(Catalog& cat, const std::string& engine, const fs::path& dir, int n, double direct_us) {
  CatalogSpool spool(cat, (dir / ("spool-" + engine + ".sqlite")).string());
  const std::string id = "spool-" + engine;
  spool.startRun(runOf(id));
  const auto t0 = Clock::now();
  for (int i = 0; i < n; ++i)
    spool.addEvent(id, "robot1", std::chrono::system_clock::now(), "INFO", "waypoint " + std::to_string(i));
  const double queued_s = secondsSince(t0);
  spool.flush(std::chrono::seconds(120));
  const double s = secondsSince(t0);
  const double us = queued_s / n * 1e6;
  return {"spool " + engine, engine, n, us, us / direct_us, s, n / s};
}

Case outage(Catalog& cat, test::OwnPostgres& pg, const fs::path& dir, int n, double direct_us) {
  CatalogSpool spool(cat, (dir / "spool-outage.sqlite").string());
  const std::string id = "outage";
  spool.startRun(runOf(id));
  spool.flush(std::chrono::seconds(30));
  pg.halt();
  const auto t0 = Clock::now();
  for (int i = 0; i < n; ++i)
    spool.addEvent(id, "robot1", std::chrono::system_clock::now(), "INFO", "during the outage " + std::to_string(i));
  const double us = secondsSince(t0) / n * 1e6;
  pg.resume();
  spool.flush(std::chrono::seconds(300));
  const auto st = spool.status();
  return {"spool postgresql, 1 outage", "postgresql", static_cast<int>(st.last_backlog), us, us / direct_us,
          st.last_catch_up_s, st.last_catch_up_s > 0 ? st.last_backlog / st.last_catch_up_s : 0};
}

}  // namespace

int main(int argc, char** argv) {
  int writes = 5000;
  std::string json_path;
  cli::readOrExit("bench_catalog", argc, argv, [&](cli::ArgReader& a) {
    if (a.isHelp()) {
      std::printf("usage: bench_catalog [--writes N] [--json FILE] [--quick]\n"
                  "The catalog's writes on the recording thread, direct and through the local spool, on SQLite and\n"
                  "PostgreSQL (a server of its own), and a spool's catch-up after PostgreSQL was stopped; a table,\n"
                  "--json writes the same figures. --quick: 500 writes.\n");
      std::exit(0);
    } else if (a.is("--writes")) writes = static_cast<int>(a.numberAbove(9));
    else if (a.is("--json")) json_path = a.path();
    else if (a.is("--quick")) writes = 500;
    else a.unknown();
  });
  const fs::path dir = fs::temp_directory_path() / ("bench_catalog_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::vector<Case> cases;
  std::string pg_error;
  try {
    auto sqlite = Catalog::open((dir / "catalog.sqlite").string());
    cases.push_back(direct(sqlite, "sqlite", writes));
    cases.push_back(spooled(sqlite, "sqlite", dir, writes, cases.back().us_per_write));
    std::optional<test::OwnPostgres> pg;
    try {
      pg.emplace();
    } catch (const std::exception& e) {
      pg_error = e.what();
    }
    if (pg) {
      if (!test::postgresQuery(pg->url(), "CREATE DATABASE bench").empty()) throw std::runtime_error("CREATE DATABASE");
      auto post = Catalog::open(pg->url("bench"));
      post.setServerId("bench");
      cases.push_back(direct(post, "postgresql", writes));
      const double direct_us = cases.back().us_per_write;
      cases.push_back(spooled(post, "postgresql", dir, writes, direct_us));
      cases.push_back(outage(post, *pg, dir, writes, direct_us));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_catalog: %s\n", e.what());
    fs::remove_all(dir);
    return 1;
  }
  fs::remove_all(dir);

  std::printf("bench_catalog: %d event writes of one run per case\n\n", writes);
  std::printf("%-28s %10s %10s %11s %14s\n", "case", "us/write", "vs direct", "through s", "through/s");
  for (const auto& c : cases)
    std::printf("%-28s %10.1f %9.2fx %11.3f %14.0f\n", c.name.c_str(), c.us_per_write, c.vs_direct, c.through_s,
                c.writes_per_s);
  std::printf("\nus/write: on the recording thread. vs direct: / the same engine's direct cost (this run).\n"
              "through: until every write was in the catalog (outage: from the first write after PostgreSQL\n"
              "came back to the last, the writes kept meanwhile).\n");
  if (!pg_error.empty()) std::printf("PostgreSQL cases skipped: %s\n", pg_error.c_str());
  if (!json_path.empty()) {
    Json j{{"writes", writes}, {"cases", Json::array()}, {"postgresql_skipped", pg_error}};
    for (const auto& c : cases)
      j["cases"].push_back({{"name", c.name}, {"engine", c.engine}, {"writes", c.writes},
                            {"us_per_write", c.us_per_write}, {"vs_direct", c.vs_direct}, {"through_s", c.through_s},
                            {"writes_per_s", c.writes_per_s}});
    std::ofstream(json_path) << j.dump(2) << "\n";
  }
  return 0;
}
