#include "tests/support/sql_query.hpp"

#include <sqlite3.h>

#include "shared/catalog/sql_backend.hpp"
#include "tests/support/postgres_server.hpp"

namespace inspect::test {

std::vector<std::string> rawQuery(const std::string& path, const std::string& sql) {
  if (catalog::isPostgresUrl(path)) return postgresQuery(path, sql);
  sqlite3* db = nullptr;
  std::vector<std::string> rows;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) == SQLITE_OK) {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &s, nullptr) == SQLITE_OK) {
      while (sqlite3_step(s) == SQLITE_ROW) {
        const auto* t = reinterpret_cast<const char*>(sqlite3_column_text(s, 0));
        rows.emplace_back(t ? t : "");
      }
    } else {
      rows.push_back(std::string("error: ") + sqlite3_errmsg(db));
    }
    sqlite3_finalize(s);
  }
  sqlite3_close(db);
  return rows;
}

}  // namespace inspect::test
