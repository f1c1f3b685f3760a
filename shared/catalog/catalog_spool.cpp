// The catalog's local spool and its writer thread (catalog_spool.hpp).
#include "shared/catalog/catalog_spool.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <random>

#include "shared/catalog/sql_backend.hpp"
#include "shared/catalog/time_text.hpp"
#include "shared/util/number_text.hpp"

namespace inspect::catalog {

namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

// The spool file's schema: one migration list, as the catalog's. seq is
// AUTOINCREMENT so that a seq is never used twice, even after the spool
// emptied: the catalog skips every seq at or below the last it applied.
constexpr std::string_view kSpoolSchema[] = {R"sql(
CREATE TABLE spool_meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE writes (
  seq         INTEGER PRIMARY KEY AUTOINCREMENT,
  op          TEXT NOT NULL,
  queued_unix REAL NOT NULL
);
)sql"};

int64_t nsOf(Time t) { return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count(); }
Time timeOf(const json& j) {
  return Time(std::chrono::duration_cast<Time::duration>(std::chrono::nanoseconds(j.get<int64_t>())));
}

// JSON has no NaN: null stands for it.
json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
double numberOf(const json& j) { return j.is_number() ? j.get<double>() : std::nan(""); }
json optional(const std::optional<double>& v) { return v ? json(*v) : json(nullptr); }
std::optional<double> optionalOf(const json& j) {
  return j.is_number() ? std::optional<double>(j.get<double>()) : std::nullopt;
}

std::string newSpoolId() {
  std::random_device rd;
  char buf[40];
  std::snprintf(buf, sizeof buf, "spool-%08x%08x", rd(), rd());
  return buf;
}

std::string seconds(double s) { return util::fmtFixed(s, 2) + " s"; }

}  // namespace

CatalogSpool::CatalogSpool(Catalog& catalog, const std::string& path) : CatalogSpool(catalog, path, Options{}) {}

CatalogSpool::CatalogSpool(Catalog& catalog, const std::string& path, Options options)
    : catalog_(catalog), path_(path), options_(options) {
  file_ = openSqlite(path, kSpoolSchema);
  const auto meta = file_->run("SELECT value FROM spool_meta WHERE key = 'spool_id'", {});
  if (meta.rows.empty()) {
    id_ = newSpoolId();
    file_->run("INSERT INTO spool_meta (key, value) VALUES ('spool_id', ?)", {id_});
  } else {
    id_ = std::get<std::string>(meta.rows[0][0]);
  }
  // What an earlier process left (the catalog was away when it stopped).
  const auto left = file_->run("SELECT count(*), COALESCE(min(seq), 0), COALESCE(max(seq), 0) FROM writes", {});
  const auto& row = left.rows.at(0);
  status_.pending = std::get<int64_t>(row[0]);
  done_seq_ = status_.pending ? std::get<int64_t>(row[1]) - 1 : 0;
  queued_seq_ = std::get<int64_t>(row[2]);
  writer_ = std::thread([this] { writerLoop(); });
}

CatalogSpool::~CatalogSpool() {
  if (status().reachable) flush(options_.close_wait);
  {
    std::lock_guard lk(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  writer_.join();
}

// --- the writes ------------------------------------------------------------

void CatalogSpool::queue(const std::string& op) {
  int64_t seq = 0;
  {
    std::lock_guard lk(file_mu_);
    const auto r = file_->run("INSERT INTO writes (op, queued_unix) VALUES (?, ?) RETURNING seq",
                              {op, unixSeconds(std::chrono::system_clock::now())});
    seq = std::get<int64_t>(r.rows.at(0).at(0));
  }
  {
    std::lock_guard lk(mu_);
    queued_seq_ = std::max(queued_seq_, seq);
    ++status_.pending;
  }
  cv_.notify_all();
}

void CatalogSpool::upsertRobot(const std::string& robot, const std::string& software_version, Time now) {
  queue(json{{"op", "robot"}, {"robot", robot}, {"sw", software_version}, {"t", nsOf(now)}}.dump());
}

void CatalogSpool::startRun(const RunStart& r) {
  if (r.id.empty()) failCatalog(path_, "a spooled run start needs its id");
  const Time start = r.start.value_or(std::chrono::system_clock::now());
  queue(json{{"op", "start"}, {"id", r.id}, {"robot", r.robot}, {"name", r.name}, {"route", r.route},
             {"gains", r.gains_json}, {"sw", r.software_version}, {"dir", r.dir}, {"t", nsOf(start)}}
            .dump());
}

void CatalogSpool::endRun(const std::string& run_id, const std::string& outcome, Time end) {
  queue(json{{"op", "end"}, {"run", run_id}, {"outcome", outcome}, {"t", nsOf(end)}}.dump());
}

void CatalogSpool::setGains(const std::string& run_id, const std::string& gains_json) {
  queue(json{{"op", "gains"}, {"run", run_id}, {"gains", gains_json}}.dump());
}

void CatalogSpool::addEvent(const std::string& run_id, const std::string& robot, Time t, const std::string& kind,
                            const std::string& text) {
  queue(json{{"op", "event"}, {"run", run_id}, {"robot", robot}, {"t", nsOf(t)}, {"kind", kind}, {"text", text}}
            .dump());
}

void CatalogSpool::addAlarm(const std::string& run_id, const std::string& robot, Time t, const std::string& channel,
                            const std::string& level, const std::string& state, double value, double x_m,
                            double y_m) {
  queue(json{{"op", "alarm"}, {"run", run_id}, {"robot", robot}, {"t", nsOf(t)}, {"channel", channel},
             {"level", level}, {"state", state}, {"value", number(value)}, {"x", number(x_m)}, {"y", number(y_m)}}
            .dump());
}

void CatalogSpool::setSummary(const std::string& run_id, const Summary& s) {
  json gas = json::array();
  for (const auto& g : s.gas)
    gas.push_back({{"channel", g.channel}, {"unit", g.unit}, {"max", number(g.max)}, {"mean", number(g.mean)}});
  queue(json{{"op", "summary"},
             {"run", run_id},
             {"duration_s", number(s.duration_s)},
             {"distance_m", number(s.distance_m)},
             {"min_person_m", optional(s.min_person_m)},
             {"track_max_pos_err_m", optional(s.track_max_pos_err_m)},
             {"track_rms_pos_err_m", optional(s.track_rms_pos_err_m)},
             {"track_max_angle_err_rad", optional(s.track_max_angle_err_rad)},
             {"video_frames_received", s.video_frames_received},
             {"video_frames_decoded", s.video_frames_decoded},
             {"video_packets_lost", s.video_packets_lost},
             {"gas", gas}}
            .dump());
}

void CatalogSpool::addFile(const std::string& run_id, const std::string& kind, const std::string& path,
                           int64_t bytes) {
  queue(json{{"op", "file"}, {"run", run_id}, {"kind", kind}, {"path", path}, {"bytes", bytes}}.dump());
}

void CatalogSpool::upsertServer(const ServerInfo& sv) {
  {
    std::lock_guard lk(mu_);
    server_latest_ = sv;
    ++latest_queued_;
  }
  cv_.notify_all();
}

void CatalogSpool::setPresence(const RobotPresence& p) {
  {
    std::lock_guard lk(mu_);
    presence_latest_[p.robot] = p;
    ++latest_queued_;
  }
  cv_.notify_all();
}

void CatalogSpool::apply(const std::string& text) {
  const json j = json::parse(text);
  const std::string op = j.at("op");
  if (op == "robot") {
    catalog_.upsertRobot(j.at("robot"), j.at("sw"), timeOf(j.at("t")));
  } else if (op == "start") {
    RunStart r;
    r.id = j.at("id");
    r.robot = j.at("robot");
    r.name = j.at("name");
    r.route = j.at("route");
    r.gains_json = j.at("gains");
    r.software_version = j.at("sw");
    r.dir = j.at("dir");
    r.start = timeOf(j.at("t"));
    catalog_.startRun(r);
  } else if (op == "end") {
    catalog_.endRun(j.at("run"), j.at("outcome"), timeOf(j.at("t")));
  } else if (op == "gains") {
    catalog_.setGains(j.at("run"), j.at("gains"));
  } else if (op == "event") {
    catalog_.addEvent(j.at("run"), j.at("robot"), timeOf(j.at("t")), j.at("kind"), j.at("text"));
  } else if (op == "alarm") {
    catalog_.addAlarm(j.at("run"), j.at("robot"), timeOf(j.at("t")), j.at("channel"), j.at("level"), j.at("state"),
                      numberOf(j.at("value")), numberOf(j.at("x")), numberOf(j.at("y")));
  } else if (op == "summary") {
    Summary s;
    s.duration_s = numberOf(j.at("duration_s"));
    s.distance_m = numberOf(j.at("distance_m"));
    s.min_person_m = optionalOf(j.at("min_person_m"));
    s.track_max_pos_err_m = optionalOf(j.at("track_max_pos_err_m"));
    s.track_rms_pos_err_m = optionalOf(j.at("track_rms_pos_err_m"));
    s.track_max_angle_err_rad = optionalOf(j.at("track_max_angle_err_rad"));
    s.video_frames_received = j.at("video_frames_received");
    s.video_frames_decoded = j.at("video_frames_decoded");
    s.video_packets_lost = j.at("video_packets_lost");
    for (const auto& g : j.at("gas"))
      s.gas.push_back({g.at("channel"), g.at("unit"), numberOf(g.at("max")), numberOf(g.at("mean"))});
    catalog_.setSummary(j.at("run"), s);
  } else if (op == "file") {
    catalog_.addFile(j.at("run"), j.at("kind"), j.at("path"), j.at("bytes"));
  } else {
    failCatalog(path_, "unknown spooled write '" + op + "'");
  }
}

// --- the writer ------------------------------------------------------------

bool CatalogSpool::writeBatch(int limit) {
  std::vector<int64_t> seqs;
  std::vector<std::string> ops;
  {
    std::lock_guard lk(file_mu_);
    for (auto& row : file_->run("SELECT seq, op FROM writes ORDER BY seq LIMIT ?", {int64_t{limit}}).rows) {
      seqs.push_back(std::get<int64_t>(row[0]));
      ops.push_back(std::move(std::get<std::string>(row[1])));
    }
  }
  if (seqs.empty()) return false;
  bool refused = false;
  std::string why;
  int64_t ran = 0;
  try {
    ran = catalog_.applySpooled(id_, seqs, [&](std::size_t i) { apply(ops[i]); });
  } catch (const CatalogUnavailable&) {
    throw;
  } catch (const std::exception& e) {  // the catalog refused a write, or a spooled write is unreadable
    if (seqs.size() > 1) {
      // Find which: one at a time (the batch's rows are the spool's first), so that the others go through.
      for (std::size_t i = 0; i < seqs.size(); ++i) writeBatch(1);
      return true;
    }
    refused = true;
    why = e.what();
  }
  {
    std::lock_guard lk(file_mu_);
    file_->run("DELETE FROM writes WHERE seq <= ?", {seqs.back()});
  }
  {
    // One step under the lock: a flush that returns sees the state after it.
    std::lock_guard lk(mu_);
    done_seq_ = std::max(done_seq_, seqs.back());
    status_.pending -= static_cast<int64_t>(seqs.size());
    status_.written += ran;
    if (refused) ++status_.dropped;
    wroteLocked();
  }
  if (refused) {
    const std::string op = ops[0].substr(0, 120);
    notice("catalog " + catalog_.path() + ": a write was refused and is dropped (spool seq " +
           std::to_string(seqs[0]) + ", " + op + "): " + why);
  }
  cv_.notify_all();
  return true;
}

void CatalogSpool::writerLoop() {
  auto retry = options_.retry_first;
  for (;;) {
    {
      std::unique_lock lk(mu_);
      if (away_since_) {
        cv_.wait_for(lk, retry, [&] { return stop_; });
      } else {
        cv_.wait(lk, [&] { return stop_ || done_seq_ < queued_seq_ || latest_done_ < latest_queued_; });
      }
      if (stop_) return;
      attempt_ = Clock::now();
      attempt_pending_ = status_.pending;
    }
    try {
      // A batch at a time; the lock is not held while the catalog writes.
      while (writeBatch(options_.batch)) {
        std::lock_guard lk(mu_);
        if (stop_) return;
      }
      writeLatest();
      retry = options_.retry_first;
    } catch (const std::exception& e) {  // CatalogUnavailable, or the spool file itself failing
      wentAway(e.what());
      retry = std::min(options_.retry_max, retry * 2);
    }
  }
}

void CatalogSpool::writeLatest() {
  std::optional<ServerInfo> server;
  std::map<std::string, RobotPresence> presence;
  uint64_t generation = 0;
  {
    std::lock_guard lk(mu_);
    if (latest_done_ == latest_queued_) return;
    server.swap(server_latest_);
    presence.swap(presence_latest_);
    generation = latest_queued_;
  }
  try {
    if (server) catalog_.upsertServer(*server);
    for (const auto& [robot, p] : presence) catalog_.setPresence(p);
  } catch (const CatalogUnavailable&) {
    std::lock_guard lk(mu_);  // kept for the next try, unless newer ones came meanwhile
    if (!server_latest_) server_latest_ = std::move(server);
    for (auto& [robot, p] : presence) presence_latest_.try_emplace(robot, std::move(p));
    throw;
  } catch (const std::exception& e) {
    notice("catalog " + catalog_.path() + ": the server's or a robot's presence row was refused: " + e.what());
  }
  {
    std::lock_guard lk(mu_);
    latest_done_ = std::max(latest_done_, generation);
    wroteLocked();
  }
  cv_.notify_all();
}

void CatalogSpool::wentAway(const std::string& why) {
  std::lock_guard lk(mu_);
  status_.error = why;
  if (away_since_) return;
  away_since_ = Clock::now();
  catching_up_since_.reset();
  status_.reachable = false;
  notices_.push_back(why + "; recording goes on, the catalog's writes kept in " + path_ + " until it is back");
}

void CatalogSpool::wroteLocked() {
  if (away_since_) cameBackLocked();
  if (catching_up_since_ && status_.pending == 0) caughtUpLocked();
}

void CatalogSpool::cameBackLocked() {
  away_s_ = std::chrono::duration<double>(attempt_ - *away_since_).count();
  away_since_.reset();
  catching_up_since_ = attempt_;
  backlog_ = attempt_pending_;
  status_.reachable = true;
  status_.error.clear();
}

void CatalogSpool::caughtUpLocked() {
  status_.last_catch_up_s = std::chrono::duration<double>(Clock::now() - *catching_up_since_).count();
  status_.last_backlog = backlog_;
  catching_up_since_.reset();
  notices_.push_back("catalog " + catalog_.path() + ": back after " + seconds(away_s_) + " away; " +
                     std::to_string(backlog_) + " writes kept meanwhile written through in " +
                     seconds(status_.last_catch_up_s));
}

void CatalogSpool::notice(std::string text) {
  std::lock_guard lk(mu_);
  notices_.push_back(std::move(text));
}

bool CatalogSpool::flush(std::chrono::milliseconds timeout) {
  std::unique_lock lk(mu_);
  const int64_t target = queued_seq_;
  const uint64_t latest = latest_queued_;
  cv_.notify_all();
  return cv_.wait_for(lk, timeout, [&] { return done_seq_ >= target && latest_done_ >= latest; });
}

SpoolStatus CatalogSpool::status() const {
  std::lock_guard lk(mu_);
  SpoolStatus s = status_;
  if (away_since_) s.away_s = std::chrono::duration<double>(Clock::now() - *away_since_).count();
  return s;
}

std::vector<std::string> CatalogSpool::noticesSince(uint64_t& cursor) const {
  std::lock_guard lk(mu_);
  std::vector<std::string> out;
  for (auto i = static_cast<std::size_t>(cursor); i < notices_.size(); ++i) out.push_back(notices_[i]);
  cursor = notices_.size();
  return out;
}

}  // namespace inspect::catalog
