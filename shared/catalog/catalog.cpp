#include "shared/catalog/catalog.hpp"
#include "shared/catalog/time_text.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <mutex>
#include <type_traits>
#include <unordered_map>

namespace inspect::catalog {

namespace {

// PRAGMA application_id of a catalog ("INSP"): tells it from other SQLite files.
constexpr int32_t kApplicationId = 0x494E5350;
constexpr int kBusyTimeoutMs = 5000;
constexpr int kMaxRunIdSuffix = 10000;


// Adds a robot (id, software_version, time), completed by what to do if it exists.
#define INSERT_ROBOT                                                                                   \
  "INSERT INTO robots (id, software_version, first_seen, first_seen_unix, last_seen, last_seen_unix)" \
  " VALUES (?1, ?2, ?3, ?4, ?3, ?4) ON CONFLICT (id) DO "

// Columns read into a TuningSession by readTuningSession(), in this order.
#define TUNING_COLUMNS                                                                                          \
  "id, session_id, created_unix, COALESCE(robot_id, ''), reference, plant_json, params, algorithm, evals,"     \
  " wall_s, cancelled, initial_cost, best_cost, initial_gains_json, best_gains_json, dir"

// Columns read into a GainsPush by readGainsPush(), in this order.
#define PUSH_COLUMNS "id, robot_id, time_unix, version, gains_json, status, reason, COALESCE(session_id, '')"

// Columns read into a RunInfo by readRun(), in this order.
#define RUN_COLUMNS \
  "id, run_id, robot_id, name, route, gains_json, software_version, dir, start_unix, end_unix, COALESCE(outcome, '')"

std::string sanitizeRobotId(const std::string& robot) {
  std::string out = robot;
  for (char& c : out) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
                    c == '.' || c == '-';
    if (!ok) c = '_';
  }
  return out;
}

bool isOutcome(std::string_view s) {
  return std::find(std::begin(kOutcomes), std::end(kOutcomes), s) != std::end(kOutcomes);
}

bool isPushStatus(std::string_view s) {
  return std::find(std::begin(kPushStatuses), std::end(kPushStatuses), s) != std::end(kPushStatuses);
}

// Costs that are not finite (no evaluation finished) are stored as NULL and read back as NaN.
std::optional<double> finiteOrNull(double v) { return std::isfinite(v) ? std::optional<double>(v) : std::nullopt; }

bool allDigits(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

std::optional<std::string_view> nullIfEmpty(const std::string& s) {
  return s.empty() ? std::nullopt : std::optional<std::string_view>(s);
}

struct StmtFinalizer {
  void operator()(sqlite3_stmt* s) const { sqlite3_finalize(s); }
};
struct DbCloser {
  void operator()(sqlite3* d) const { sqlite3_close_v2(d); }
};

}  // namespace

// ---------------------------------------------------------------------------

struct Catalog::Impl {
  std::string path;
  std::unique_ptr<sqlite3, DbCloser> db;  // declared before `cache`: closed after the statements
  std::unordered_map<std::string_view, std::unique_ptr<sqlite3_stmt, StmtFinalizer>> cache;
  std::mutex mu;

  [[noreturn]] void fail(const std::string& what) const {
    std::string msg = "catalog " + path + ": " + what;
    if (db) msg += std::string(": ") + sqlite3_errmsg(db.get());
    throw CatalogError(msg);
  }
  [[noreturn]] void failPlain(const std::string& what) const { throw CatalogError("catalog " + path + ": " + what); }

  void exec(const char* sql, const char* what) {
    if (sqlite3_exec(db.get(), sql, nullptr, nullptr, nullptr) != SQLITE_OK) fail(what);
  }

  // A cached prepared statement, reset and unbound when the Query goes.
  class Query {
   public:
    Query(Impl& impl, sqlite3_stmt* s) : impl_(impl), s_(s) {}
    Query(const Query&) = delete;
    Query& operator=(const Query&) = delete;
    ~Query() {
      sqlite3_reset(s_);
      sqlite3_clear_bindings(s_);
    }

    // Binds the arguments to ?1, ?2, ... in order; a Time takes two: ISO text, unix seconds.
    template <class... A>
    Query& bind(const A&... a) {
      int i = 0;
      (bindOne(i, a), ...);
      return *this;
    }
    // True: a row is ready; false: done. Throws on error.
    bool step() {
      const int rc = sqlite3_step(s_);
      if (rc == SQLITE_ROW) return true;
      if (rc == SQLITE_DONE) return false;
      impl_.fail(std::string("cannot run '") + sqlite3_sql(s_) + "'");
    }
    void run() {
      while (step()) {
      }
    }

    // Reads columns 0, 1, ... of the current row into the arguments in order
    // (a Time from unix seconds; an optional stays empty for NULL).
    template <class... A>
    void read(A&... a) const {
      int c = 0;
      (readOne(c++, a), ...);
    }
    template <class T>
    T column(int c) const {
      T v{};
      readOne(c, v);
      return v;
    }

   private:
    void readOne(int c, std::string& v) const {
      const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(s_, c));
      v = p ? std::string(p, static_cast<std::size_t>(sqlite3_column_bytes(s_, c))) : std::string();
    }
    void readOne(int c, double& v) const { v = sqlite3_column_double(s_, c); }
    void readOne(int c, int64_t& v) const { v = sqlite3_column_int64(s_, c); }
    void readOne(int c, Time& v) const { v = fromUnix(sqlite3_column_double(s_, c)); }
    template <class T>
    void readOne(int c, std::optional<T>& v) const {
      if (sqlite3_column_type(s_, c) == SQLITE_NULL) {
        v.reset();
      } else {
        readOne(c, v.emplace());
      }
    }

    void check(int rc) {
      if (rc != SQLITE_OK) impl_.fail("cannot bind a parameter");
    }
    void bindOne(int& i, std::string_view v) {
      check(sqlite3_bind_text(s_, ++i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT));
    }
    void bindOne(int& i, const std::string& v) { bindOne(i, std::string_view(v)); }
    void bindOne(int& i, const char* v) { bindOne(i, std::string_view(v)); }
    void bindOne(int& i, double v) { check(sqlite3_bind_double(s_, ++i, v)); }
    void bindOne(int& i, int64_t v) { check(sqlite3_bind_int64(s_, ++i, v)); }
    void bindOne(int& i, int v) { check(sqlite3_bind_int64(s_, ++i, v)); }
    void bindOne(int& i, Time t) {
      bindOne(i, formatIsoUtc(t));
      bindOne(i, unixSeconds(t));
    }
    template <class T>
    void bindOne(int& i, const std::optional<T>& v) {
      static_assert(!std::is_same_v<T, Time>, "an empty optional<Time> would bind one NULL for two parameters");
      if (v) {
        bindOne(i, *v);
      } else {
        check(sqlite3_bind_null(s_, ++i));
      }
    }

    Impl& impl_;
    sqlite3_stmt* s_;
  };

  // `sql` must outlive the Catalog (a literal): it keys the cache.
  Query query(std::string_view sql) {
    auto& slot = cache[sql];
    if (!slot) {
      sqlite3_stmt* s = nullptr;
      if (sqlite3_prepare_v2(db.get(), sql.data(), static_cast<int>(sql.size()), &s, nullptr) != SQLITE_OK)
        fail("cannot prepare '" + std::string(sql) + "'");
      slot.reset(s);
    }
    return Query(*this, slot.get());
  }

  // A transaction rolled back unless committed.
  class Tx {
   public:
    explicit Tx(Impl& impl, const char* begin = "BEGIN IMMEDIATE") : impl_(impl) {
      impl_.exec(begin, "cannot begin a transaction");
    }
    Tx(const Tx&) = delete;
    Tx& operator=(const Tx&) = delete;
    ~Tx() {
      if (!done_) sqlite3_exec(impl_.db.get(), "ROLLBACK", nullptr, nullptr, nullptr);
    }
    void commit() {
      impl_.exec("COMMIT", "cannot commit");
      done_ = true;
    }

   private:
    Impl& impl_;
    bool done_ = false;
  };

  int64_t pragmaInt(std::string_view sql) {
    auto q = query(sql);
    return q.step() ? q.column<int64_t>(0) : 0;
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

  void migrate(std::span<const std::string_view> migrations) {
    const auto known = static_cast<int64_t>(migrations.size());
    Tx tx(*this);
    checkIsCatalog(known);  // again, in the transaction: another process may have migrated meanwhile
    const int64_t version = pragmaInt("PRAGMA user_version");
    for (int64_t v = version; v < known; ++v) {
      const std::string sql(migrations[static_cast<std::size_t>(v)]);
      if (sqlite3_exec(db.get(), sql.c_str(), nullptr, nullptr, nullptr) != SQLITE_OK)
        fail("migration " + std::to_string(v + 1));
    }
    if (version < known) {
      exec(("PRAGMA user_version = " + std::to_string(known)).c_str(), "cannot set user_version");
      exec(("PRAGMA application_id = " + std::to_string(kApplicationId)).c_str(), "cannot set application_id");
    }
    tx.commit();
  }

  RunInfo readRun(const Query& q) const {
    RunInfo r;
    q.read(r.rowid, r.id, r.robot, r.name, r.route, r.gains_json, r.software_version, r.dir, r.start, r.end, r.outcome);
    return r;
  }

  std::optional<RunInfo> findRun(const std::string& run_id) {
    auto q = allDigits(run_id) ? query("SELECT " RUN_COLUMNS " FROM runs WHERE id = ?")
                               : query("SELECT " RUN_COLUMNS " FROM runs WHERE run_id = ?");
    if (allDigits(run_id)) {
      q.bind(static_cast<int64_t>(std::stoll(run_id)));
    } else {
      q.bind(run_id);
    }
    if (!q.step()) return std::nullopt;
    return readRun(q);
  }

  TuningSession readTuningSession(const Query& q) const {
    TuningSession s;
    int64_t cancelled = 0;
    std::optional<double> initial_cost, best_cost;
    q.read(s.rowid, s.id, s.created, s.robot, s.reference, s.plant_json, s.params, s.algorithm, s.evals, s.wall_s,
           cancelled, initial_cost, best_cost, s.initial_gains_json, s.best_gains_json, s.dir);
    s.cancelled = cancelled != 0;
    s.initial_cost = initial_cost.value_or(std::nan(""));
    s.best_cost = best_cost.value_or(std::nan(""));
    return s;
  }

  GainsPush readGainsPush(const Query& q) const {
    GainsPush p;
    q.read(p.rowid, p.robot, p.time, p.version, p.gains_json, p.status, p.reason, p.session_id);
    return p;
  }

  std::optional<Summary> readSummary(const std::string& run_id) {
    auto q = query(
        "SELECT duration_s, distance_m, min_person_m, track_max_pos_err_m, track_rms_pos_err_m,"
        " track_max_angle_err_rad, video_frames_received, video_frames_decoded, video_packets_lost"
        " FROM run_summary WHERE run_id = ?");
    q.bind(run_id);
    if (!q.step()) return std::nullopt;
    Summary s;
    q.read(s.duration_s, s.distance_m, s.min_person_m, s.track_max_pos_err_m, s.track_rms_pos_err_m,
           s.track_max_angle_err_rad, s.video_frames_received, s.video_frames_decoded, s.video_packets_lost);
    auto g = query("SELECT channel, unit, max, mean FROM run_gas WHERE run_id = ? ORDER BY channel");
    g.bind(run_id);
    while (g.step()) {
      auto& gas = s.gas.emplace_back();
      g.read(gas.channel, gas.unit, gas.max, gas.mean);
    }
    return s;
  }
};

// ---------------------------------------------------------------------------

Catalog::Catalog(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Catalog::Catalog(Catalog&&) noexcept = default;
Catalog& Catalog::operator=(Catalog&&) noexcept = default;
Catalog::~Catalog() = default;

Catalog Catalog::open(const std::string& path) { return open(path, schemaMigrations()); }

Catalog Catalog::open(const std::string& path, std::span<const std::string_view> migrations) {
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  sqlite3* raw = nullptr;
  const int rc = sqlite3_open_v2(path.c_str(), &raw, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX,
                                 nullptr);
  impl->db.reset(raw);
  if (rc != SQLITE_OK) impl->fail("cannot open");
  sqlite3_extended_result_codes(raw, 1);
  sqlite3_busy_timeout(raw, kBusyTimeoutMs);
  impl->exec("SELECT count(*) FROM sqlite_master", "cannot read");  // not a database, unreadable, ...
  impl->checkIsCatalog(static_cast<int64_t>(migrations.size()));  // before WAL changes the file
  {
    auto q = impl->query("PRAGMA journal_mode = WAL");
    const std::string mode = q.step() ? q.column<std::string>(0) : std::string();
    if (mode != "wal") impl->failPlain("cannot use WAL (journal_mode is '" + mode + "')");
  }
  impl->exec("PRAGMA synchronous = NORMAL", "cannot set synchronous");
  impl->exec("PRAGMA foreign_keys = ON", "cannot enable foreign keys");
  impl->migrate(migrations);
  return Catalog(std::move(impl));
}

const std::string& Catalog::path() const { return impl_->path; }

int Catalog::schemaVersion() {
  std::lock_guard lk(impl_->mu);
  return static_cast<int>(impl_->pragmaInt("PRAGMA user_version"));
}

void Catalog::upsertRobot(const std::string& robot, const std::string& software_version, Time now) {
  std::lock_guard lk(impl_->mu);
  impl_->query(INSERT_ROBOT
               "UPDATE SET software_version = excluded.software_version, last_seen = excluded.last_seen,"
               " last_seen_unix = excluded.last_seen_unix")
      .bind(robot, software_version, now)
      .run();
}

RunInfo Catalog::startRun(const RunStart& r) {
  if (r.robot.empty()) impl_->failPlain("a run needs a robot id");
  std::lock_guard lk(impl_->mu);
  const Time start = r.start.value_or(std::chrono::system_clock::now());
  Impl::Tx tx(*impl_);
  impl_->query(INSERT_ROBOT "NOTHING")
      .bind(r.robot, r.software_version, start)
      .run();
  const std::string base = strftimeUtc(start, "%Y%m%d-%H%M%S-") + sanitizeRobotId(r.robot);
  std::string id;
  for (int n = 1;; ++n) {
    if (n > kMaxRunIdSuffix) impl_->failPlain("no free run id for " + base);
    id = n == 1 ? base : base + "-" + std::to_string(n);
    auto q = impl_->query("SELECT 1 FROM runs WHERE run_id = ?");
    if (!q.bind(id).step()) break;
  }
  impl_->query(
           "INSERT INTO runs (run_id, robot_id, name, route, gains_json, software_version, dir, start_time, start_unix)"
           " VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)")
      .bind(id, r.robot, r.name, r.route, r.gains_json, r.software_version, r.dir, start)
      .run();
  const int64_t rowid = sqlite3_last_insert_rowid(impl_->db.get());
  tx.commit();
  return RunInfo{rowid, id, r.robot, r.name, r.route, r.gains_json, r.software_version, r.dir, start, {}, {}};
}

bool Catalog::endRun(const std::string& run_id, const std::string& outcome, Time end) {
  if (!isOutcome(outcome)) impl_->failPlain("unknown outcome '" + outcome + "'");
  std::lock_guard lk(impl_->mu);
  impl_->query("UPDATE runs SET end_time = ?, end_unix = ?, outcome = ? WHERE run_id = ? AND end_time IS NULL")
      .bind(end, outcome, run_id)
      .run();
  if (sqlite3_changes(impl_->db.get()) == 1) return true;
  auto q = impl_->query("SELECT 1 FROM runs WHERE run_id = ?");
  if (!q.bind(run_id).step()) impl_->failPlain("no run '" + run_id + "'");
  return false;
}

void Catalog::setGains(const std::string& run_id, const std::string& gains_json) {
  std::lock_guard lk(impl_->mu);
  impl_->query("UPDATE runs SET gains_json = ? WHERE run_id = ?").bind(gains_json, run_id).run();
  if (sqlite3_changes(impl_->db.get()) != 1) impl_->failPlain("no run '" + run_id + "'");
}

std::optional<RunInfo> Catalog::activeRun(const std::string& robot) {
  std::lock_guard lk(impl_->mu);
  auto q = impl_->query("SELECT " RUN_COLUMNS
                        " FROM runs WHERE robot_id = ? AND end_time IS NULL ORDER BY start_unix DESC, id DESC LIMIT 1");
  if (!q.bind(robot).step()) return std::nullopt;
  return impl_->readRun(q);
}

std::vector<std::string> Catalog::markIncompleteRuns() {
  std::lock_guard lk(impl_->mu);
  Impl::Tx tx(*impl_);
  std::vector<std::pair<std::string, double>> open;
  {
    auto q = impl_->query(
        "SELECT run_id, max(start_unix,"
        " COALESCE((SELECT max(time_unix) FROM events e WHERE e.run_id = r.run_id), 0),"
        " COALESCE((SELECT max(time_unix) FROM alarms a WHERE a.run_id = r.run_id), 0))"
        " FROM runs r WHERE end_time IS NULL ORDER BY start_unix, id");
    while (q.step()) {
      auto& [id, last] = open.emplace_back();
      q.read(id, last);
    }
  }
  std::vector<std::string> ids;
  for (const auto& [id, last] : open) {
    impl_->query("UPDATE runs SET end_time = ?, end_unix = ?, outcome = 'incomplete' WHERE run_id = ?")
        .bind(fromUnix(last), id)
        .run();
    ids.push_back(id);
  }
  tx.commit();
  return ids;
}

void Catalog::addEvent(const std::string& run_id, const std::string& robot, Time t, const std::string& kind,
                       const std::string& text) {
  std::lock_guard lk(impl_->mu);
  impl_->query("INSERT INTO events (run_id, robot_id, time, time_unix, kind, text) VALUES (?, ?, ?, ?, ?, ?)")
      .bind(nullIfEmpty(run_id), robot, t, kind, text)
      .run();
}

void Catalog::addAlarm(const std::string& run_id, const std::string& robot, Time t, const std::string& channel,
                       const std::string& level, const std::string& state, double value, double x_m, double y_m) {
  std::lock_guard lk(impl_->mu);
  impl_->query(
           "INSERT INTO alarms (run_id, robot_id, time, time_unix, channel, level, state, value, x_m, y_m)"
           " VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)")
      .bind(nullIfEmpty(run_id), robot, t, channel, level, state, value, x_m, y_m)
      .run();
}

void Catalog::setSummary(const std::string& run_id, const Summary& s) {
  std::lock_guard lk(impl_->mu);
  Impl::Tx tx(*impl_);
  impl_->query(
           "INSERT OR REPLACE INTO run_summary (run_id, duration_s, distance_m, min_person_m, track_max_pos_err_m,"
           " track_rms_pos_err_m, track_max_angle_err_rad, video_frames_received, video_frames_decoded,"
           " video_packets_lost) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)")
      .bind(run_id, s.duration_s, s.distance_m, s.min_person_m, s.track_max_pos_err_m, s.track_rms_pos_err_m,
            s.track_max_angle_err_rad, s.video_frames_received, s.video_frames_decoded, s.video_packets_lost)
      .run();
  impl_->query("DELETE FROM run_gas WHERE run_id = ?").bind(run_id).run();
  for (const auto& g : s.gas)
    impl_->query("INSERT INTO run_gas (run_id, channel, unit, max, mean) VALUES (?, ?, ?, ?, ?)")
        .bind(run_id, g.channel, g.unit, g.max, g.mean)
        .run();
  tx.commit();
}

void Catalog::addFile(const std::string& run_id, const std::string& kind, const std::string& path, int64_t bytes) {
  std::lock_guard lk(impl_->mu);
  impl_->query(
           "INSERT INTO run_files (run_id, kind, path, bytes) VALUES (?, ?, ?, ?)"
           " ON CONFLICT (run_id, path) DO UPDATE SET kind = excluded.kind, bytes = excluded.bytes")
      .bind(run_id, kind, path, bytes)
      .run();
}

std::vector<RunInfo> Catalog::listRuns(const RunFilter& f) {
  if (!f.outcome.empty() && f.outcome != "running" && !isOutcome(f.outcome))
    impl_->failPlain("unknown outcome '" + f.outcome + "'");
  std::optional<double> since;
  if (f.since) since = unixSeconds(*f.since);
  std::lock_guard lk(impl_->mu);
  auto q = impl_->query("SELECT " RUN_COLUMNS
                        " FROM runs WHERE (?1 IS NULL OR robot_id = ?1)"
                        " AND (?2 IS NULL OR instr(lower(name), lower(?2)) > 0)"
                        " AND (?3 IS NULL OR outcome = ?3 OR (?3 = 'running' AND outcome IS NULL))"
                        " AND (?4 IS NULL OR start_unix >= ?4)"
                        " ORDER BY start_unix DESC, id DESC LIMIT ?5");
  q.bind(nullIfEmpty(f.robot), nullIfEmpty(f.name_contains), nullIfEmpty(f.outcome), since,
         f.limit > 0 ? f.limit : -1);
  std::vector<RunInfo> out;
  while (q.step()) out.push_back(impl_->readRun(q));
  return out;
}

std::optional<RunDetail> Catalog::run(const std::string& run_id) {
  std::lock_guard lk(impl_->mu);
  Impl::Tx tx(*impl_, "BEGIN");  // one snapshot for all the reads
  RunDetail d;
  if (auto info = impl_->findRun(run_id)) {
    d.info = std::move(*info);
  } else {
    return std::nullopt;
  }
  const std::string& id = d.info.id;
  d.summary = impl_->readSummary(id);
  {
    auto q = impl_->query("SELECT kind, path, bytes FROM run_files WHERE run_id = ? ORDER BY id");
    q.bind(id);
    while (q.step()) {
      auto& file = d.files.emplace_back();
      q.read(file.kind, file.path, file.bytes);
    }
  }
  {
    auto q = impl_->query(
        "SELECT (SELECT count(*) FROM events WHERE run_id = ?1), (SELECT count(*) FROM alarms WHERE run_id = ?1)");
    if (q.bind(id).step()) q.read(d.event_count, d.alarm_count);
  }
  tx.commit();
  return d;
}

void Catalog::addTuningSession(const TuningSession& s) {
  if (s.id.empty()) impl_->failPlain("a tuning session needs an id");
  std::lock_guard lk(impl_->mu);
  {
    auto q = impl_->query("SELECT 1 FROM tuning_sessions WHERE session_id = ?");
    if (q.bind(s.id).step()) impl_->failPlain("tuning session '" + s.id + "' is already recorded");
  }
  impl_->query(
           "INSERT INTO tuning_sessions (session_id, created_time, created_unix, robot_id, reference, plant_json,"
           " params, algorithm, evals, wall_s, cancelled, initial_cost, best_cost, initial_gains_json,"
           " best_gains_json, dir) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)")
      .bind(s.id, s.created, nullIfEmpty(s.robot), s.reference, s.plant_json, s.params, s.algorithm, s.evals,
            s.wall_s, int64_t{s.cancelled ? 1 : 0}, finiteOrNull(s.initial_cost), finiteOrNull(s.best_cost),
            s.initial_gains_json, s.best_gains_json, s.dir)
      .run();
}

std::vector<TuningSession> Catalog::listTuningSessions(int limit) {
  std::lock_guard lk(impl_->mu);
  auto q = impl_->query("SELECT " TUNING_COLUMNS " FROM tuning_sessions ORDER BY created_unix DESC, id DESC LIMIT ?");
  q.bind(limit > 0 ? limit : -1);
  std::vector<TuningSession> out;
  while (q.step()) out.push_back(impl_->readTuningSession(q));
  return out;
}

std::optional<TuningSession> Catalog::tuningSession(const std::string& id) {
  std::lock_guard lk(impl_->mu);
  auto q = impl_->query("SELECT " TUNING_COLUMNS " FROM tuning_sessions WHERE session_id = ?");
  if (!q.bind(id).step()) return std::nullopt;
  return impl_->readTuningSession(q);
}

void Catalog::addGainsPush(const GainsPush& p) {
  if (p.robot.empty()) impl_->failPlain("a gains push needs a robot id");
  if (!isPushStatus(p.status)) impl_->failPlain("unknown gains push status '" + p.status + "' (accepted, rejected)");
  std::lock_guard lk(impl_->mu);
  impl_->query(
           "INSERT INTO gains_pushes (robot_id, time, time_unix, version, gains_json, status, reason, session_id)"
           " VALUES (?, ?, ?, ?, ?, ?, ?, ?)")
      .bind(p.robot, p.time, p.version, p.gains_json, p.status, p.reason, nullIfEmpty(p.session_id))
      .run();
}

std::vector<GainsPush> Catalog::listGainsPushes(const std::string& robot, int limit) {
  std::lock_guard lk(impl_->mu);
  auto q = impl_->query("SELECT " PUSH_COLUMNS
                        " FROM gains_pushes WHERE (?1 IS NULL OR robot_id = ?1)"
                        " ORDER BY time_unix DESC, id DESC LIMIT ?2");
  q.bind(nullIfEmpty(robot), limit > 0 ? limit : -1);
  std::vector<GainsPush> out;
  while (q.step()) out.push_back(impl_->readGainsPush(q));
  return out;
}

std::string Catalog::integrityCheck() {
  std::lock_guard lk(impl_->mu);
  auto q = impl_->query("PRAGMA integrity_check");
  std::string out;
  while (q.step()) out += (out.empty() ? "" : "\n") + q.column<std::string>(0);
  return out;
}

}  // namespace inspect::catalog
