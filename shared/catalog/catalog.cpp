// The run catalog's runs, events, alarms, summaries and files (docs/catalog.md);
// Catalog::Impl is in catalog_impl.hpp.
#include <algorithm>
#include <cstdio>
#include <ctime>

#include "shared/catalog/catalog_impl.hpp"

namespace inspect::catalog {

void failCatalog(const std::string& where, const std::string& what) { throw CatalogError("catalog " + where + ": " + what); }
void failUnavailable(const std::string& where, const std::string& what) {
  throw CatalogUnavailable("catalog " + where + ": " + what);
}

namespace {

constexpr int kMaxRunIdSuffix = 10000;
using detail::limitOf;
using detail::nullIfEmpty;

// Adds a robot (id, software_version, time), completed by what to do if it exists.
#define INSERT_ROBOT                                                                                   \
  "INSERT INTO robots (id, software_version, first_seen, first_seen_unix, last_seen, last_seen_unix)" \
  " VALUES (?1, ?2, ?3, ?4, ?3, ?4) ON CONFLICT (id) DO "

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

}  // namespace

std::string runIdBase(const std::string& robot, Time start) {
  return strftimeUtc(start, "%Y%m%d-%H%M%S-") + sanitizeRobotId(robot);
}

Catalog::Catalog(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Catalog::Catalog(Catalog&&) noexcept = default;
Catalog& Catalog::operator=(Catalog&&) noexcept = default;
Catalog::~Catalog() = default;

Catalog Catalog::open(const std::string& path) { return open(path, schemaMigrations()); }

Catalog Catalog::open(const std::string& path, std::span<const std::string_view> migrations) {
  auto impl = std::make_unique<Impl>();
  impl->db = isPostgresUrl(path) ? openPostgres(path, migrations) : openSqlite(path, migrations);
  impl->fleet = migrations.size() >= detail::kServerIdsVersion;
  return Catalog(std::move(impl));
}

const std::string& Catalog::path() const { return impl_->db->where(); }

int Catalog::schemaVersion() {
  std::lock_guard lk(impl_->mu);
  return static_cast<int>(impl_->db->schemaVersion());
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
  const std::string base = r.id.empty() ? runIdBase(r.robot, start) : r.id;
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
    if (!r.id.empty()) {
      // The id was given: the same run written again (a spool's replay) is that row.
      auto old = impl_->findRun(id);
      if (old && old->robot == r.robot && old->server == impl_->server_id &&
          std::abs(unixSeconds(old->start) - unixSeconds(start)) < 1e-3) {
        tx.commit();
        return *old;
      }
      impl_->failPlain("run id '" + id + "' is taken by another run" +
                       (old && !old->server.empty() ? " (server " + old->server + ")" : ""));
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

std::string Catalog::integrityCheck() {
  std::lock_guard lk(impl_->mu);
  return impl_->db->integrityCheck();
}

}  // namespace inspect::catalog
