#pragma once
// A real PostgreSQL server for the tests (tests/support/pg_cluster.sh): the
// one the ctest fixture `postgres` started (its directory in the file that
// $INSPECT_TEST_PG_FILE names), else one started for this process on first
// use and stopped at its exit (a test program run by hand, the sanitizer
// stage). Unix socket only, trust authentication for the role `inspect`.
#include <string>
#include <vector>

namespace inspect::test {

/// The server's socket directory; throws std::runtime_error when none can be started.
const std::string& postgresDir();
/// A URL of database `db` on it: "postgresql:///<db>?host=<dir>&user=inspect".
std::string postgresUrl(const std::string& db = "postgres");
/// Creates a new, empty database (its name from `tag`, this process and a
/// counter; at most 63 characters) and returns its URL.
std::string freshPostgresDatabase(const std::string& tag);
/// Runs SQL on database `db` as `inspect`; the first column of each row
/// ("error: ..." when it fails).
std::vector<std::string> postgresQuery(const std::string& url, const std::string& sql);

/// A PostgreSQL server of one test's own, for a test that stops it (an
/// outage): the suite's shared server stays up for the other tests.
class OwnPostgres {
 public:
  OwnPostgres();   // starts it (1-4 s); throws std::runtime_error
  ~OwnPostgres();  // stops it and removes its directory
  OwnPostgres(const OwnPostgres&) = delete;
  OwnPostgres& operator=(const OwnPostgres&) = delete;
  /// A URL of database `db` on it.
  std::string url(const std::string& db = "postgres") const;
  /// Stops the server, keeping its data (pg_ctl stop -m fast), and starts it again.
  void halt();
  void resume();

 private:
  std::string file_, dir_;
};

}  // namespace inspect::test
