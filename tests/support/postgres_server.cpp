#include "tests/support/postgres_server.hpp"

#include <libpq-fe.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <mutex>
#include <stdexcept>

#include "tests/support/paths.hpp"

namespace inspect::test {

namespace {

std::string readLine(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

std::string ownFile;  // the file of a server this process started ("" = the fixture's)

void cluster(const std::string& command, const std::string& file) {
  const std::string cmd =
      "bash '" + srcPath("tests/support/pg_cluster.sh") + "' " + command + " '" + file + "' >/dev/null";
  if (std::system(cmd.c_str()) != 0)
    throw std::runtime_error("pg_cluster.sh " + command + " " + file + " failed");
}

void stopOwn() {
  if (ownFile.empty()) return;
  const std::string cmd = "bash '" + srcPath("tests/support/pg_cluster.sh") + "' stop '" + ownFile + "' >/dev/null 2>&1";
  [[maybe_unused]] const int rc = std::system(cmd.c_str());
}

std::string startOwn() {
  ownFile = "/tmp/inspect-pg-own-" + std::to_string(::getpid());
  cluster("start", ownFile);
  std::atexit(stopOwn);
  return readLine(ownFile);
}

}  // namespace

const std::string& postgresDir() {
  static std::once_flag once;
  static std::string dir;
  std::call_once(once, [] {
    if (const char* f = std::getenv("INSPECT_TEST_PG_FILE"); f && *f) dir = readLine(f);
    if (dir.empty()) dir = startOwn();
  });
  return dir;
}

std::string postgresUrl(const std::string& db) { return "postgresql:///" + db + "?host=" + postgresDir() + "&user=inspect"; }

std::vector<std::string> postgresQuery(const std::string& url, const std::string& sql) {
  std::vector<std::string> rows;
  PGconn* c = PQconnectdb(url.c_str());
  if (PQstatus(c) != CONNECTION_OK) {
    rows.push_back(std::string("error: ") + PQerrorMessage(c));
    PQfinish(c);
    return rows;
  }
  PGresult* r = PQexec(c, sql.c_str());
  const auto st = PQresultStatus(r);
  if (st == PGRES_TUPLES_OK) {
    for (int i = 0; i < PQntuples(r); ++i) rows.emplace_back(PQgetisnull(r, i, 0) ? "" : PQgetvalue(r, i, 0));
  } else if (st != PGRES_COMMAND_OK) {
    rows.push_back(std::string("error: ") + PQresultErrorMessage(r));
  }
  PQclear(r);
  PQfinish(c);
  return rows;
}

std::string freshPostgresDatabase(const std::string& tag) {
  static std::atomic<int> counter{0};
  std::string name = "t" + std::to_string(::getpid()) + "_" + std::to_string(++counter) + "_";
  for (char c : tag) {
    if (name.size() >= 63) break;
    name += (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : ((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9')) ? c : '_';
  }
  const auto r = postgresQuery(postgresUrl(), "CREATE DATABASE " + name);
  if (!r.empty()) throw std::runtime_error("cannot create database " + name + ": " + r.front());
  return postgresUrl(name);
}

OwnPostgres::OwnPostgres() {
  static std::atomic<int> counter{0};
  file_ = "/tmp/inspect-pg-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
  cluster("start", file_);
  dir_ = readLine(file_);
}

OwnPostgres::~OwnPostgres() {
  try {
    cluster("stop", file_);
  } catch (const std::exception&) {  // nothing more to do in a destructor
  }
}

std::string OwnPostgres::url(const std::string& db) const {
  return "postgresql:///" + db + "?host=" + dir_ + "&user=inspect";
}

void OwnPostgres::halt() { cluster("halt", file_); }
void OwnPostgres::resume() { cluster("resume", file_); }

}  // namespace inspect::test
