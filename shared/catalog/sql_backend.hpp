#pragma once
// The run catalog's database engines behind one interface (docs/catalog.md):
// SQLite (one file, the default) and PostgreSQL (a fleet's shared catalog).
// The catalog's queries are written once, in the SQL both understand, with
// `?` / `?N` parameters; a back-end runs them, keeps the schema version and
// applies the migrations in its own way, and names itself in every error.
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace inspect::catalog {

/// A parameter or a cell: NULL, a whole number, a number or text.
using SqlValue = std::variant<std::monostate, int64_t, double, std::string>;

struct SqlResult {
  std::vector<std::vector<SqlValue>> rows;
  int64_t changed = 0;  // rows inserted, updated or deleted
};

class SqlBackend {
 public:
  virtual ~SqlBackend() = default;
  /// The file path, or the URL without its password: errors name it.
  virtual const std::string& where() const = 0;
  /// Runs one statement; `sql` outlives the back-end (a literal: it keys the
  /// prepared statements). Throws CatalogError naming where() and the reason.
  virtual SqlResult run(std::string_view sql, const std::vector<SqlValue>& params) = 0;
  /// A write transaction (taken at once), or a read snapshot.
  virtual void begin(bool write) = 0;
  virtual void commit() = 0;
  /// Never throws (called from destructors).
  virtual void rollback() noexcept = 0;
  /// The number of migrations applied.
  virtual int64_t schemaVersion() = 0;
  /// Applies the migrations not yet applied, all in one transaction, after
  /// checking that the database is a catalog (or empty) and not newer.
  virtual void migrate(std::span<const std::string_view> migrations) = 0;
  /// "ok", or the engine's complaints one per line.
  virtual std::string integrityCheck() = 0;
};

/// Throws CatalogError "catalog <where>: <what>": every catalog error's form.
[[noreturn]] void failCatalog(const std::string& where, const std::string& what);
/// The same as CatalogUnavailable: the engine cannot be reached.
[[noreturn]] void failUnavailable(const std::string& where, const std::string& what);

/// True for "postgresql://..." and "postgres://..." (libpq's URLs).
bool isPostgresUrl(std::string_view target);
/// The URL without its password ("postgresql://inspect@db/fleet").
std::string redactUrl(const std::string& url);

std::unique_ptr<SqlBackend> openSqlite(const std::string& path, std::span<const std::string_view> migrations);
/// Connects with libpq: the password from the URL, ~/.pgpass, PGPASSFILE or
/// PGPASSWORD, never from the command line.
std::unique_ptr<SqlBackend> openPostgres(const std::string& url, std::span<const std::string_view> migrations);

/// The SQLite schema script as PostgreSQL reads it: identity keys, 64-bit
/// integers, double-precision reals. The one place the two schemas differ.
std::string postgresDdl(std::string_view sqlite_ddl);
/// `?` and `?N` parameters as `$N`.
std::string postgresParams(std::string_view sql);

}  // namespace inspect::catalog
