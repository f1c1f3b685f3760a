// The catalog on PostgreSQL (libpq): a fleet's servers share one database.
// The schema is the SQLite one read by postgresDdl; the version and the
// application are rows of catalog_meta; migrations run under an advisory
// lock, so two servers starting at once migrate once.
#include <libpq-fe.h>

#include <cstdio>
#include <cstdlib>
#include <regex>
#include <unordered_map>

#include "shared/catalog/catalog.hpp"
#include "shared/catalog/sql_backend.hpp"

namespace inspect::catalog {

namespace {

constexpr const char* kApplication = "inspect-run-catalog";
// pg_type OIDs of the numeric types (catalog/pg_type_d.h, stable since 7.x).
constexpr Oid kInt8 = 20, kInt2 = 21, kInt4 = 23, kFloat4 = 700, kFloat8 = 701, kNumeric = 1700;

// SQLite's instr(), which the catalog's name filter uses.
constexpr const char* kPrelude =
    "CREATE OR REPLACE FUNCTION instr(haystack text, needle text) RETURNS integer"
    " LANGUAGE sql IMMUTABLE AS 'SELECT strpos(haystack, needle)';";

struct ResultClear {
  void operator()(PGresult* r) const { PQclear(r); }
};
using Result = std::unique_ptr<PGresult, ResultClear>;
struct ConnFinish {
  void operator()(PGconn* c) const { PQfinish(c); }
};

// libpq waits for ever by default: a server gone from the network would
// hold the catalog's writer (and a shutdown) until TCP gives up. Unless the
// URL says otherwise: 10 s to connect, and a dead peer noticed in about 30 s.
std::string withTimeouts(const std::string& url) {
  std::string out = url;
  for (const char* opt : {"connect_timeout=10", "keepalives_idle=15", "keepalives_interval=5", "keepalives_count=3"}) {
    const std::string key = std::string(opt).substr(0, std::string(opt).find('=') + 1);
    if (out.find(key) != std::string::npos) continue;
    out += (out.find('?') == std::string::npos ? "?" : "&");
    out += opt;
  }
  return out;
}

std::string firstLine(const char* msg) {
  std::string s = msg ? msg : "";
  if (const auto nl = s.find('\n'); nl != std::string::npos) s.resize(nl);
  return s;
}

class PostgresBackend final : public SqlBackend {
 public:
  explicit PostgresBackend(const std::string& url) : url_(withTimeouts(url)), where_(redactUrl(url)) {}

  void open(std::span<const std::string_view> migrations) {
    conn_.reset(PQconnectdb(url_.c_str()));
    if (!conn_ || PQstatus(conn_.get()) != CONNECTION_OK)
      failUnavailable(where_, "cannot connect: " + firstLine(conn_ ? PQerrorMessage(conn_.get()) : "out of memory"));
    PQsetNoticeProcessor(conn_.get(), [](void*, const char*) {}, nullptr);  // "already exists" notices
    migrate(migrations);
  }

  const std::string& where() const override { return where_; }

  SqlResult run(std::string_view sql, const std::vector<SqlValue>& params) override {
    reconnectIfLost();
    const std::string& name = prepare(sql);
    std::vector<std::string> texts(params.size());
    std::vector<const char*> values(params.size(), nullptr);
    for (std::size_t i = 0; i < params.size(); ++i) {
      const SqlValue& v = params[i];
      if (std::holds_alternative<std::monostate>(v)) continue;
      if (const auto* n = std::get_if<int64_t>(&v)) texts[i] = std::to_string(*n);
      else if (const auto* d = std::get_if<double>(&v)) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.17g", *d);
        texts[i] = buf;
      } else texts[i] = std::get<std::string>(v);
      values[i] = texts[i].c_str();
    }
    Result r(PQexecPrepared(conn_.get(), name.c_str(), static_cast<int>(values.size()), values.data(), nullptr,
                            nullptr, 0));
    check(r.get(), "cannot run '" + std::string(sql) + "'");
    SqlResult out;
    const int rows = PQntuples(r.get()), cols = PQnfields(r.get());
    out.rows.reserve(static_cast<std::size_t>(rows));
    for (int i = 0; i < rows; ++i) {
      auto& row = out.rows.emplace_back();
      for (int c = 0; c < cols; ++c) row.push_back(cell(r.get(), i, c));
    }
    out.changed = std::atoll(PQcmdTuples(r.get()));
    return out;
  }

  void begin(bool write) override {
    reconnectIfLost();
    exec(write ? "BEGIN" : "BEGIN ISOLATION LEVEL REPEATABLE READ", "cannot begin a transaction");
  }
  void commit() override { exec("COMMIT", "cannot commit"); }
  void rollback() noexcept override {
    if (conn_ && PQstatus(conn_.get()) == CONNECTION_OK && PQtransactionStatus(conn_.get()) != PQTRANS_IDLE)
      Result(PQexec(conn_.get(), "ROLLBACK"));
  }

  int64_t schemaVersion() override {
    const auto r = run("SELECT value FROM catalog_meta WHERE key = 'schema_version'", {});
    return r.rows.empty() ? 0 : std::atoll(std::get<std::string>(r.rows[0][0]).c_str());
  }

  void migrate(std::span<const std::string_view> migrations) override {
    const auto known = static_cast<int64_t>(migrations.size());
    begin(true);
    try {
      exec("SELECT pg_advisory_xact_lock(hashtext('inspect-run-catalog'))", "cannot lock the schema");
      const int64_t version = checkIsCatalog(known);
      if (version == 0) {
        exec("CREATE TABLE catalog_meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)", "cannot create catalog_meta");
        exec(kPrelude, "cannot create instr()");
        run("INSERT INTO catalog_meta (key, value) VALUES ('application', ?)", {std::string(kApplication)});
        run("INSERT INTO catalog_meta (key, value) VALUES ('schema_version', '0')", {});
      }
      for (int64_t v = version; v < known; ++v) {
        const std::string ddl = postgresDdl(migrations[static_cast<std::size_t>(v)]);
        exec(ddl.c_str(), ("migration " + std::to_string(v + 1)).c_str());
      }
      if (version < known)
        run("UPDATE catalog_meta SET value = ? WHERE key = 'schema_version'", {std::to_string(known)});
      commit();
    } catch (...) {
      rollback();
      throw;
    }
  }

  std::string integrityCheck() override {
    // PostgreSQL checks its pages itself (checksums, WAL); what can be wrong
    // here is a catalog without its tables.
    run("SELECT count(*) FROM runs", {});
    return "ok";
  }

 private:
  [[noreturn]] void failPlain(const std::string& what) const { failCatalog(where_, what); }

  void check(PGresult* r, const std::string& what) {
    const auto st = r ? PQresultStatus(r) : PGRES_FATAL_ERROR;
    if (st == PGRES_COMMAND_OK || st == PGRES_TUPLES_OK) return;
    const std::string reason = firstLine(r ? PQresultErrorMessage(r) : PQerrorMessage(conn_.get()));
    // The connection gone (the server stopped, the network cut): a later try
    // may work, and which statement it cut short says nothing to the operator.
    if (PQstatus(conn_.get()) != CONNECTION_OK) failUnavailable(where_, "connection lost: " + reason);
    failPlain(what + ": " + reason);
  }

  void exec(const char* sql, const char* what) {
    Result r(PQexec(conn_.get(), sql));
    check(r.get(), what);
  }

  // A lost connection (the server restarted, the network came back) is
  // tried again once per call outside a transaction; inside one, the call fails.
  void reconnectIfLost() {
    if (PQstatus(conn_.get()) == CONNECTION_OK) return;
    PQreset(conn_.get());
    prepared_.clear();
    if (PQstatus(conn_.get()) != CONNECTION_OK)
      failUnavailable(where_, "connection lost: " + firstLine(PQerrorMessage(conn_.get())));
  }

  const std::string& prepare(std::string_view sql) {
    auto& name = prepared_[sql];
    if (name.empty()) {
      const std::string n = "q" + std::to_string(next_name_++);
      Result r(PQprepare(conn_.get(), n.c_str(), postgresParams(sql).c_str(), 0, nullptr));
      check(r.get(), "cannot prepare '" + std::string(sql) + "'");
      name = n;
    }
    return name;
  }

  static SqlValue cell(PGresult* r, int row, int col) {
    if (PQgetisnull(r, row, col)) return std::monostate{};
    const char* v = PQgetvalue(r, row, col);
    switch (PQftype(r, col)) {
      case kInt8:
      case kInt4:
      case kInt2: return static_cast<int64_t>(std::atoll(v));
      case kFloat4:
      case kFloat8:
      case kNumeric: return std::strtod(v, nullptr);
      default: return std::string(v, static_cast<std::size_t>(PQgetlength(r, row, col)));
    }
  }

  // The version of the catalog in this database (0: none yet); throws unless
  // it is empty or a catalog not newer than `known`.
  int64_t checkIsCatalog(int64_t known) {
    const auto meta = run("SELECT to_regclass('catalog_meta') IS NOT NULL", {});
    const bool has_meta = !meta.rows.empty() && std::get<std::string>(meta.rows[0][0]) == "t";
    if (!has_meta) {
      const auto tables =
          run("SELECT count(*) FROM information_schema.tables WHERE table_schema = current_schema()", {});
      if (std::get<int64_t>(tables.rows[0][0]) > 0)
        failPlain("not a run catalog (has tables but no catalog_meta)");
      return 0;
    }
    const auto app = run("SELECT value FROM catalog_meta WHERE key = 'application'", {});
    if (app.rows.empty() || std::get<std::string>(app.rows[0][0]) != kApplication)
      failPlain("not a run catalog (catalog_meta names another application)");
    const int64_t version = schemaVersion();
    if (version > known)
      failPlain("schema version " + std::to_string(version) + " was written by a newer program (this one knows up to " +
                std::to_string(known) + "); use a newer build or another database");
    return version;
  }

  std::string url_;    // with its password, for PQreset's reconnection only
  std::string where_;  // without
  std::unique_ptr<PGconn, ConnFinish> conn_;
  std::unordered_map<std::string_view, std::string> prepared_;
  int next_name_ = 1;
};

}  // namespace

bool isPostgresUrl(std::string_view target) {
  return target.rfind("postgresql://", 0) == 0 || target.rfind("postgres://", 0) == 0;
}

std::string redactUrl(const std::string& url) {
  std::string out = url;
  // postgresql://user:secret@host/db -> postgresql://user@host/db
  if (const auto scheme = out.find("://"); scheme != std::string::npos) {
    const auto start = scheme + 3;
    const auto at = out.find('@', start);
    const auto slash = out.find('/', start);
    if (at != std::string::npos && (slash == std::string::npos || at < slash)) {
      const auto colon = out.find(':', start);
      if (colon != std::string::npos && colon < at) out.erase(colon, at - colon);
    }
  }
  // ...?password=secret&x=y -> ...?password=***&x=y
  static const std::regex kPassword("([?&]password=)[^&]*");
  return std::regex_replace(out, kPassword, "$1***");
}

std::string postgresDdl(std::string_view sqlite_ddl) {
  static const std::regex kRowid("INTEGER PRIMARY KEY");
  static const std::regex kInteger("\\bINTEGER\\b");
  static const std::regex kReal("\\bREAL\\b");
  std::string s(sqlite_ddl);
  s = std::regex_replace(s, kRowid, "BIGINT GENERATED BY DEFAULT AS IDENTITY PRIMARY KEY");
  s = std::regex_replace(s, kInteger, "BIGINT");
  return std::regex_replace(s, kReal, "DOUBLE PRECISION");
}

std::string postgresParams(std::string_view sql) {
  std::string out;
  out.reserve(sql.size() + 16);
  int next = 0;
  bool quoted = false;
  for (std::size_t i = 0; i < sql.size(); ++i) {
    const char c = sql[i];
    if (c == '\'') quoted = !quoted;
    if (c != '?' || quoted) {
      out += c;
      continue;
    }
    out += '$';
    if (i + 1 < sql.size() && sql[i + 1] >= '0' && sql[i + 1] <= '9') continue;  // ?N: the digits follow
    out += std::to_string(++next);
  }
  return out;
}

std::unique_ptr<SqlBackend> openPostgres(const std::string& url, std::span<const std::string_view> migrations) {
  auto b = std::make_unique<PostgresBackend>(url);
  b->open(migrations);
  return b;
}

}  // namespace inspect::catalog
