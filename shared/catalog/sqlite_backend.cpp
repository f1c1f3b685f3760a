// The catalog on SQLite: one file, WAL, synchronous=NORMAL, foreign keys, a
// busy timeout; PRAGMA user_version is the schema version and
// application_id tells a catalog from other SQLite files.
#include <sqlite3.h>

#include <unordered_map>

#include "shared/catalog/catalog.hpp"
#include "shared/catalog/sql_backend.hpp"

namespace inspect::catalog {

namespace {

// PRAGMA application_id of a catalog ("INSP").
constexpr int32_t kApplicationId = 0x494E5350;
constexpr int kBusyTimeoutMs = 5000;

struct StmtFinalizer {
  void operator()(sqlite3_stmt* s) const { sqlite3_finalize(s); }
};
struct DbCloser {
  void operator()(sqlite3* d) const { sqlite3_close_v2(d); }
};

class SqliteBackend final : public SqlBackend {
 public:
  explicit SqliteBackend(std::string path) : path_(std::move(path)) {}

  void open(std::span<const std::string_view> migrations) {
    sqlite3* raw = nullptr;
    const int rc = sqlite3_open_v2(path_.c_str(), &raw,
                                   SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX, nullptr);
    db_.reset(raw);
    if (rc != SQLITE_OK) fail("cannot open");
    sqlite3_extended_result_codes(raw, 1);
    sqlite3_busy_timeout(raw, kBusyTimeoutMs);
    exec("SELECT count(*) FROM sqlite_master", "cannot read");  // not a database, unreadable, ...
    checkIsCatalog(static_cast<int64_t>(migrations.size()));   // before WAL changes the file
    const auto mode = run("PRAGMA journal_mode = WAL", {});
    const std::string m = mode.rows.empty() ? "" : std::get<std::string>(mode.rows[0][0]);
    if (m != "wal") failPlain("cannot use WAL (journal_mode is '" + m + "')");
    exec("PRAGMA synchronous = NORMAL", "cannot set synchronous");
    exec("PRAGMA foreign_keys = ON", "cannot enable foreign keys");
    migrate(migrations);
  }

  const std::string& where() const override { return path_; }

  SqlResult run(std::string_view sql, const std::vector<SqlValue>& params) override {
    sqlite3_stmt* s = prepare(sql);
    struct Reset {
      sqlite3_stmt* s;
      ~Reset() {
        sqlite3_reset(s);
        sqlite3_clear_bindings(s);
      }
    } reset{s};
    for (std::size_t i = 0; i < params.size(); ++i) bind(s, static_cast<int>(i + 1), params[i]);
    SqlResult out;
    for (;;) {
      const int rc = sqlite3_step(s);
      if (rc == SQLITE_DONE) break;
      if (rc != SQLITE_ROW) fail(std::string("cannot run '") + sqlite3_sql(s) + "'");
      auto& row = out.rows.emplace_back();
      const int n = sqlite3_column_count(s);
      for (int c = 0; c < n; ++c) row.push_back(cell(s, c));
    }
    out.changed = sqlite3_changes(db_.get());
    return out;
  }

  void begin(bool write) override { exec(write ? "BEGIN IMMEDIATE" : "BEGIN", "cannot begin a transaction"); }
  void commit() override { exec("COMMIT", "cannot commit"); }
  void rollback() noexcept override { sqlite3_exec(db_.get(), "ROLLBACK", nullptr, nullptr, nullptr); }

  int64_t schemaVersion() override { return pragmaInt("PRAGMA user_version"); }

  void migrate(std::span<const std::string_view> migrations) override {
    const auto known = static_cast<int64_t>(migrations.size());
    begin(true);
    try {
      checkIsCatalog(known);  // again, in the transaction: another process may have migrated meanwhile
      const int64_t version = schemaVersion();
      for (int64_t v = version; v < known; ++v) {
        const std::string sql(migrations[static_cast<std::size_t>(v)]);
        if (sqlite3_exec(db_.get(), sql.c_str(), nullptr, nullptr, nullptr) != SQLITE_OK)
          fail("migration " + std::to_string(v + 1));
      }
      if (version < known) {
        exec(("PRAGMA user_version = " + std::to_string(known)).c_str(), "cannot set user_version");
        exec(("PRAGMA application_id = " + std::to_string(kApplicationId)).c_str(), "cannot set application_id");
      }
      commit();
    } catch (...) {
      rollback();
      throw;
    }
  }

  std::string integrityCheck() override {
    std::string out;
    for (const auto& row : run("PRAGMA integrity_check", {}).rows)
      out += (out.empty() ? "" : "\n") + std::get<std::string>(row[0]);
    return out;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    if (!db_) failCatalog(path_, what);
    const std::string why = what + ": " + sqlite3_errmsg(db_.get());
    // Another writer holding the file past the busy timeout: a later try may work.
    const int rc = sqlite3_errcode(db_.get());
    if (rc == SQLITE_BUSY || rc == SQLITE_LOCKED) failUnavailable(path_, why);
    failCatalog(path_, why);
  }
  [[noreturn]] void failPlain(const std::string& what) const { failCatalog(path_, what); }

  void exec(const char* sql, const char* what) {
    if (sqlite3_exec(db_.get(), sql, nullptr, nullptr, nullptr) != SQLITE_OK) fail(what);
  }

  sqlite3_stmt* prepare(std::string_view sql) {
    auto& slot = cache_[sql];
    if (!slot) {
      sqlite3_stmt* s = nullptr;
      if (sqlite3_prepare_v2(db_.get(), sql.data(), static_cast<int>(sql.size()), &s, nullptr) != SQLITE_OK)
        fail("cannot prepare '" + std::string(sql) + "'");
      slot.reset(s);
    }
    return slot.get();
  }

  void bind(sqlite3_stmt* s, int i, const SqlValue& v) {
    int rc = SQLITE_OK;
    if (std::holds_alternative<std::monostate>(v)) rc = sqlite3_bind_null(s, i);
    else if (const auto* n = std::get_if<int64_t>(&v)) rc = sqlite3_bind_int64(s, i, *n);
    else if (const auto* d = std::get_if<double>(&v)) rc = sqlite3_bind_double(s, i, *d);
    else {
      const auto& t = std::get<std::string>(v);
      rc = sqlite3_bind_text(s, i, t.data(), static_cast<int>(t.size()), SQLITE_TRANSIENT);
    }
    if (rc != SQLITE_OK) fail("cannot bind a parameter");
  }

  static SqlValue cell(sqlite3_stmt* s, int c) {
    switch (sqlite3_column_type(s, c)) {
      case SQLITE_NULL: return std::monostate{};
      case SQLITE_INTEGER: return static_cast<int64_t>(sqlite3_column_int64(s, c));
      case SQLITE_FLOAT: return sqlite3_column_double(s, c);
      default: {
        const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(s, c));
        return p ? std::string(p, static_cast<std::size_t>(sqlite3_column_bytes(s, c))) : std::string();
      }
    }
  }

  int64_t pragmaInt(std::string_view sql) {
    const auto r = run(sql, {});
    if (r.rows.empty()) return 0;
    const auto* n = std::get_if<int64_t>(&r.rows[0][0]);
    return n ? *n : 0;
  }

  // Throws unless the file is new or a catalog of a schema version <= known.
  void checkIsCatalog(int64_t known) {
    const int64_t app = pragmaInt("PRAGMA application_id");
    const int64_t version = pragmaInt("PRAGMA user_version");
    if (app != 0 && app != kApplicationId) failPlain("not a run catalog (another program's SQLite file)");
    if (version > known)
      failPlain("schema version " + std::to_string(version) + " was written by a newer program (this one knows up to " +
                std::to_string(known) + "); use a newer build or another file");
    if (version == 0 && app == 0 && pragmaInt("SELECT count(*) FROM sqlite_master") > 0)
      failPlain("not a run catalog (has tables but no catalog schema version)");
  }

  std::string path_;
  std::unique_ptr<sqlite3, DbCloser> db_;  // declared before `cache_`: closed after the statements
  std::unordered_map<std::string_view, std::unique_ptr<sqlite3_stmt, StmtFinalizer>> cache_;
};

}  // namespace

std::unique_ptr<SqlBackend> openSqlite(const std::string& path, std::span<const std::string_view> migrations) {
  auto b = std::make_unique<SqliteBackend>(path);
  b->open(migrations);
  return b;
}

}  // namespace inspect::catalog
