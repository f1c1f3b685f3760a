#include "shared/catalog/catalog.hpp"
#include "shared/catalog/sql_backend.hpp"
#include "shared/catalog/time_text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <mutex>
#include <type_traits>

namespace inspect::catalog {

namespace {

constexpr int kMaxRunIdSuffix = 10000;
// "No limit" for LIMIT ?: both engines take the largest 64-bit integer.
// A parameter that may be NULL is CAST where it is first used (`CAST(?1 AS
// TEXT) IS NULL OR ...`): PostgreSQL must know its type, SQLite reads the
// same CAST (DOUBLE PRECISION has REAL affinity there).
constexpr int64_t kNoLimit = std::numeric_limits<int64_t>::max();

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
#define RUN_COLUMNS                                                                                                \
  "id, run_id, robot_id, name, route, gains_json, software_version, dir, start_unix, end_unix, COALESCE(outcome, ''),"  \
  " server_id"


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

int64_t limitOf(int limit) { return limit > 0 ? limit : kNoLimit; }

}  // namespace

// ---------------------------------------------------------------------------

struct Catalog::Impl {
  std::unique_ptr<SqlBackend> db;
  std::mutex mu;
  std::string server_id;
  bool fleet = true;  // the schema has version 5's server columns (false only when opened older, in tests)

  [[noreturn]] void failPlain(const std::string& what) const {
    throw CatalogError("catalog " + db->where() + ": " + what);
  }

  // A statement, its parameters bound in order, then its rows read.
  class Query {
   public:
    Query(Impl& impl, std::string_view sql) : impl_(impl), sql_(sql) {}
    Query(const Query&) = delete;
    Query& operator=(const Query&) = delete;

    // Binds the arguments to ?1, ?2, ... in order; a Time takes two: ISO text, unix seconds.
    template <class... A>
    Query& bind(const A&... a) {
      (bindOne(a), ...);
      return *this;
    }
    // True: a row is ready; false: done. Runs the statement at the first call.
    bool step() {
      if (!ran_) {
        result_ = impl_.db->run(sql_, params_);
        ran_ = true;
        row_ = 0;
      } else {
        ++row_;
      }
      return row_ < result_.rows.size();
    }
    // Runs the statement; the rows it changed.
    int64_t run() {
      step();
      return result_.changed;
    }

    // Reads columns 0, 1, ... of the current row into the arguments in order
    // (a Time from unix seconds; an optional stays empty for NULL).
    template <class... A>
    void read(A&... a) const {
      std::size_t c = 0;
      (readOne(c++, a), ...);
    }
    template <class T>
    T column(std::size_t c) const {
      T v{};
      readOne(c, v);
      return v;
    }

   private:
    const SqlValue& at(std::size_t c) const { return result_.rows[row_][c]; }
    double number(std::size_t c) const {
      const SqlValue& v = at(c);
      if (const auto* d = std::get_if<double>(&v)) return *d;
      if (const auto* n = std::get_if<int64_t>(&v)) return static_cast<double>(*n);
      if (const auto* t = std::get_if<std::string>(&v)) return std::strtod(t->c_str(), nullptr);
      return 0.0;
    }
    void readOne(std::size_t c, std::string& v) const {
      const SqlValue& x = at(c);
      if (const auto* t = std::get_if<std::string>(&x)) v = *t;
      else if (const auto* n = std::get_if<int64_t>(&x)) v = std::to_string(*n);
      else v.clear();
    }
    void readOne(std::size_t c, double& v) const { v = number(c); }
    void readOne(std::size_t c, int64_t& v) const {
      const SqlValue& x = at(c);
      const auto* n = std::get_if<int64_t>(&x);
      v = n ? *n : static_cast<int64_t>(number(c));
    }
    void readOne(std::size_t c, Time& v) const { v = fromUnix(number(c)); }
    template <class T>
    void readOne(std::size_t c, std::optional<T>& v) const {
      if (std::holds_alternative<std::monostate>(at(c))) {
        v.reset();
      } else {
        readOne(c, v.emplace());
      }
    }

    void bindOne(std::string_view v) { params_.emplace_back(std::string(v)); }
    void bindOne(const std::string& v) { params_.emplace_back(v); }
    void bindOne(const char* v) { params_.emplace_back(std::string(v)); }
    void bindOne(double v) { params_.emplace_back(v); }
    void bindOne(int64_t v) { params_.emplace_back(v); }
    void bindOne(int v) { params_.emplace_back(static_cast<int64_t>(v)); }
    void bindOne(Time t) {
      bindOne(formatIsoUtc(t));
      bindOne(unixSeconds(t));
    }
    template <class T>
    void bindOne(const std::optional<T>& v) {
      static_assert(!std::is_same_v<T, Time>, "an empty optional<Time> would bind one NULL for two parameters");
      if (v) {
        bindOne(*v);
      } else {
        params_.emplace_back(std::monostate{});
      }
    }

    Impl& impl_;
    std::string_view sql_;
    std::vector<SqlValue> params_;
    SqlResult result_;
    std::size_t row_ = 0;
    bool ran_ = false;
  };

  // `sql` must outlive the Catalog (a literal): it keys the prepared statements.
  Query query(std::string_view sql) { return Query(*this, sql); }

  // A transaction rolled back unless committed.
  class Tx {
   public:
    explicit Tx(Impl& impl, bool write = true) : impl_(impl) { impl_.db->begin(write); }
    Tx(const Tx&) = delete;
    Tx& operator=(const Tx&) = delete;
    ~Tx() {
      if (!done_) impl_.db->rollback();
    }
    void commit() {
      impl_.db->commit();
      done_ = true;
    }

   private:
    Impl& impl_;
    bool done_ = false;
  };

  RunInfo readRun(const Query& q) const {
    RunInfo r;
    q.read(r.rowid, r.id, r.robot, r.name, r.route, r.gains_json, r.software_version, r.dir, r.start, r.end, r.outcome,
           r.server);
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
  impl->db = isPostgresUrl(path) ? openPostgres(path, migrations) : openSqlite(path, migrations);
  impl->fleet = migrations.size() >= 5;
  return Catalog(std::move(impl));
}

const std::string& Catalog::path() const { return impl_->db->where(); }

int Catalog::schemaVersion() {
  std::lock_guard lk(impl_->mu);
  return static_cast<int>(impl_->db->schemaVersion());
}

void Catalog::setServerId(const std::string& id) {
  std::lock_guard lk(impl_->mu);
  impl_->server_id = id;
}

const std::string& Catalog::serverId() const { return impl_->server_id; }

void Catalog::upsertServer(const ServerInfo& s) {
  if (s.id.empty()) impl_->failPlain("a server needs an id");
  std::lock_guard lk(impl_->mu);
  impl_->query(
           "INSERT INTO servers (id, attach, runs_root, software_version, started_time, started_unix, seen_time,"
           " seen_unix) VALUES (?, ?, ?, ?, ?, ?, ?, ?) ON CONFLICT (id) DO UPDATE SET attach = excluded.attach,"
           " runs_root = excluded.runs_root, software_version = excluded.software_version,"
           " started_time = excluded.started_time, started_unix = excluded.started_unix,"
           " seen_time = excluded.seen_time, seen_unix = excluded.seen_unix")
      .bind(s.id, s.attach, s.runs_root, s.software_version, s.started, s.seen)
      .run();
}

std::vector<ServerInfo> Catalog::listServers() {
  std::lock_guard lk(impl_->mu);
  auto q = impl_->query(
      "SELECT id, attach, runs_root, software_version, started_unix, seen_unix FROM servers"
      " ORDER BY seen_unix DESC, id");
  std::vector<ServerInfo> out;
  while (q.step()) {
    auto& s = out.emplace_back();
    q.read(s.id, s.attach, s.runs_root, s.software_version, s.started, s.seen);
  }
  return out;
}

void Catalog::setPresence(const RobotPresence& p) {
  if (p.robot.empty() || p.server.empty()) impl_->failPlain("a presence needs a robot and a server id");
  std::lock_guard lk(impl_->mu);
  impl_->query(
           "INSERT INTO robot_presence (robot_id, server_id, online, mode, x_m, y_m, seen_time, seen_unix)"
           " VALUES (?, ?, ?, ?, ?, ?, ?, ?) ON CONFLICT (robot_id) DO UPDATE SET server_id = excluded.server_id,"
           " online = excluded.online, mode = excluded.mode, x_m = excluded.x_m, y_m = excluded.y_m,"
           " seen_time = excluded.seen_time, seen_unix = excluded.seen_unix")
      .bind(p.robot, p.server, int64_t{p.online ? 1 : 0}, p.mode, p.x_m, p.y_m, p.seen)
      .run();
}

std::vector<RobotPresence> Catalog::listPresence() {
  std::lock_guard lk(impl_->mu);
  auto q = impl_->query(
      "SELECT robot_id, server_id, online, mode, x_m, y_m, seen_unix FROM robot_presence ORDER BY robot_id");
  std::vector<RobotPresence> out;
  while (q.step()) {
    auto& p = out.emplace_back();
    int64_t online = 0;
    q.read(p.robot, p.server, online, p.mode, p.x_m, p.y_m, p.seen);
    p.online = online != 0;
  }
  return out;
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
  int64_t rowid = 0;
  for (int n = 1;; ++n) {
    if (n > kMaxRunIdSuffix) impl_->failPlain("no free run id for " + base);
    id = n == 1 ? base : base + "-" + std::to_string(n);
    // A taken id (this server's or another's sharing the database) inserts nothing.
    auto q = impl_->fleet
                 ? impl_->query("INSERT INTO runs (run_id, robot_id, name, route, gains_json, software_version, dir,"
                                " start_time, start_unix, server_id) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)"
                                " ON CONFLICT (run_id) DO NOTHING RETURNING id")
                 : impl_->query("INSERT INTO runs (run_id, robot_id, name, route, gains_json, software_version, dir,"
                                " start_time, start_unix) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)"
                                " ON CONFLICT (run_id) DO NOTHING RETURNING id");
    q.bind(id, r.robot, r.name, r.route, r.gains_json, r.software_version, r.dir, start);
    if (impl_->fleet) q.bind(impl_->server_id);
    if (q.step()) {
      rowid = q.column<int64_t>(0);
      break;
    }
  }
  tx.commit();
  return RunInfo{rowid, id, r.robot, r.name, r.route, r.gains_json, r.software_version, r.dir, start, {}, {},
                 impl_->server_id};
}

bool Catalog::endRun(const std::string& run_id, const std::string& outcome, Time end) {
  if (!isOutcome(outcome)) impl_->failPlain("unknown outcome '" + outcome + "'");
  std::lock_guard lk(impl_->mu);
  if (impl_->query("UPDATE runs SET end_time = ?, end_unix = ?, outcome = ? WHERE run_id = ? AND end_time IS NULL")
          .bind(end, outcome, run_id)
          .run() == 1)
    return true;
  auto q = impl_->query("SELECT 1 FROM runs WHERE run_id = ?");
  if (!q.bind(run_id).step()) impl_->failPlain("no run '" + run_id + "'");
  return false;
}

void Catalog::setGains(const std::string& run_id, const std::string& gains_json) {
  std::lock_guard lk(impl_->mu);
  if (impl_->query("UPDATE runs SET gains_json = ? WHERE run_id = ?").bind(gains_json, run_id).run() != 1)
    impl_->failPlain("no run '" + run_id + "'");
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
        "SELECT run_id, start_unix,"
        " COALESCE((SELECT max(time_unix) FROM events e WHERE e.run_id = r.run_id), 0),"
        " COALESCE((SELECT max(time_unix) FROM alarms a WHERE a.run_id = r.run_id), 0)"
        " FROM runs r WHERE end_time IS NULL AND (server_id = ? OR server_id = '') ORDER BY start_unix, id");
    q.bind(impl_->server_id);
    while (q.step()) {
      auto& [id, last] = open.emplace_back();
      double event = 0, alarm = 0;
      q.read(id, last, event, alarm);
      last = std::max({last, event, alarm});
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
  if (impl_->fleet)
    impl_->query("INSERT INTO events (run_id, robot_id, time, time_unix, kind, text, server_id)"
                 " VALUES (?, ?, ?, ?, ?, ?, ?)")
        .bind(nullIfEmpty(run_id), robot, t, kind, text, impl_->server_id)
        .run();
  else
    impl_->query("INSERT INTO events (run_id, robot_id, time, time_unix, kind, text) VALUES (?, ?, ?, ?, ?, ?)")
        .bind(nullIfEmpty(run_id), robot, t, kind, text)
        .run();
}

void Catalog::addAlarm(const std::string& run_id, const std::string& robot, Time t, const std::string& channel,
                       const std::string& level, const std::string& state, double value, double x_m, double y_m) {
  std::lock_guard lk(impl_->mu);
  impl_->query(
           "INSERT INTO alarms (run_id, robot_id, time, time_unix, channel, level, state, value, x_m, y_m, server_id)"
           " VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)")
      .bind(nullIfEmpty(run_id), robot, t, channel, level, state, value, x_m, y_m, impl_->server_id)
      .run();
}

void Catalog::setSummary(const std::string& run_id, const Summary& s) {
  std::lock_guard lk(impl_->mu);
  Impl::Tx tx(*impl_);
  impl_->query(
           "INSERT INTO run_summary (run_id, duration_s, distance_m, min_person_m, track_max_pos_err_m,"
           " track_rms_pos_err_m, track_max_angle_err_rad, video_frames_received, video_frames_decoded,"
           " video_packets_lost) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)"
           " ON CONFLICT (run_id) DO UPDATE SET duration_s = excluded.duration_s, distance_m = excluded.distance_m,"
           " min_person_m = excluded.min_person_m, track_max_pos_err_m = excluded.track_max_pos_err_m,"
           " track_rms_pos_err_m = excluded.track_rms_pos_err_m,"
           " track_max_angle_err_rad = excluded.track_max_angle_err_rad,"
           " video_frames_received = excluded.video_frames_received,"
           " video_frames_decoded = excluded.video_frames_decoded, video_packets_lost = excluded.video_packets_lost")
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
                        " FROM runs WHERE (CAST(?1 AS TEXT) IS NULL OR robot_id = ?1)"
                        " AND (CAST(?2 AS TEXT) IS NULL OR instr(lower(name), lower(?2)) > 0)"
                        " AND (CAST(?3 AS TEXT) IS NULL OR outcome = ?3 OR (?3 = 'running' AND outcome IS NULL))"
                        " AND (CAST(?4 AS DOUBLE PRECISION) IS NULL OR start_unix >= ?4)"
                        " AND (CAST(?5 AS TEXT) IS NULL OR server_id = ?5)"
                        " ORDER BY start_unix DESC, id DESC LIMIT ?6");
  q.bind(nullIfEmpty(f.robot), nullIfEmpty(f.name_contains), nullIfEmpty(f.outcome), since, nullIfEmpty(f.server),
         limitOf(f.limit));
  std::vector<RunInfo> out;
  while (q.step()) out.push_back(impl_->readRun(q));
  return out;
}

std::optional<RunDetail> Catalog::run(const std::string& run_id) {
  std::lock_guard lk(impl_->mu);
  Impl::Tx tx(*impl_, false);  // one snapshot for all the reads
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
  q.bind(limitOf(limit));
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
                        " FROM gains_pushes WHERE (CAST(?1 AS TEXT) IS NULL OR robot_id = ?1)"
                        " ORDER BY time_unix DESC, id DESC LIMIT ?2");
  q.bind(nullIfEmpty(robot), limitOf(limit));
  std::vector<GainsPush> out;
  while (q.step()) out.push_back(impl_->readGainsPush(q));
  return out;
}

std::string Catalog::integrityCheck() {
  std::lock_guard lk(impl_->mu);
  return impl_->db->integrityCheck();
}

}  // namespace inspect::catalog
