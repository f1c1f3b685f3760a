#pragma once
// The run catalog: robots, runs, their events and alarms, summary figures
// and files. One SQLite file (`catalog.sqlite`, WAL) by default, or a
// PostgreSQL database that a fleet's servers share (`postgresql://...`);
// the same schema, migrations and queries on both (sql_backend.hpp). Schema
// and example queries: docs/catalog.md.
//
// One connection per Catalog, every call under a (recursive) mutex: the
// server may call from several threads, and applySpooled's writes call back. Each write is its own transaction, so what a call has
// written survives a kill of the process (SQLite: WAL, synchronous=NORMAL).
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace inspect::catalog {

using Time = std::chrono::system_clock::time_point;

/// Any failure: the message names the catalog (file, or URL without its
/// password) and gives the engine's reason.
class CatalogError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The catalog cannot be reached (PostgreSQL down, the connection lost):
/// the write may succeed later, unlike a CatalogError about the write itself.
class CatalogUnavailable : public CatalogError {
 public:
  using CatalogError::CatalogError;
};

/// How a run ended. "incomplete": the server stopped without ending it.
inline constexpr std::string_view kOutcomes[] = {"completed", "stopped", "failed", "incomplete"};

struct RunStart {
  std::string robot;             // robot id, e.g. "robot1" (added to robots if new)
  std::string name;              // free text, e.g. "night round B"
  std::string route;             // route name or file
  std::string gains_json = "{}"; // controller gains in force
  std::string software_version;
  std::string dir;               // where the run's files go
  std::optional<Time> start;     // default: now
  /// "" = the catalog picks runIdBase() with "-2", "-3"... when taken. Set:
  /// this id (a spooled start written again is the same run, not an error).
  std::string id;
};

struct RunInfo {
  int64_t rowid = 0;       // runs.id
  std::string id;          // runs.run_id, "20261122-083015-robot1"
  std::string robot, name, route, gains_json, software_version, dir;
  Time start{};
  std::optional<Time> end;
  std::string outcome;     // one of kOutcomes, "" while running
  std::string server;      // the server that recorded it ("" = a single server's catalog)
};

struct GasFigures {
  std::string channel;  // e.g. "CH4"
  std::string unit;     // e.g. "ppm", "%LEL"
  double max = 0, mean = 0;
};

struct Summary {
  double duration_s = 0, distance_m = 0;
  std::optional<double> min_person_m;  // nobody seen: none
  // Trajectory tracking (none when no path was followed).
  std::optional<double> track_max_pos_err_m, track_rms_pos_err_m, track_max_angle_err_rad;
  int64_t video_frames_received = 0, video_frames_decoded = 0, video_packets_lost = 0;
  std::vector<GasFigures> gas;  // one per channel
};

struct FileEntry {
  std::string kind;  // e.g. "log", "telemetry", "video", "plot"
  std::string path;
  int64_t bytes = 0;
};

struct RunDetail {
  RunInfo info;
  std::optional<Summary> summary;
  std::vector<FileEntry> files;
  int64_t event_count = 0, alarm_count = 0;
};

/// listRuns: every field empty/unset matches all runs.
struct RunFilter {
  std::string robot;          // exact robot id
  std::string name_contains;  // substring of the name, case-insensitive (ASCII)
  std::string outcome;        // one of kOutcomes, or "running"
  std::optional<Time> since;  // runs started at or after
  std::string server;         // exact server id
  int limit = 100;            // newest first; <= 0: no limit
};

/// A server writing into the catalog (a fleet's shared one), kept fresh by it.
struct ServerInfo {
  std::string id;
  std::string attach;            // where an operator reaches it, e.g. "ops-pc-2:7600"
  std::string runs_root;         // its runs directory (shared root or its own)
  std::string software_version;
  Time started{}, seen{};
};

/// Where a robot is: the server holding its link, as that server last wrote.
struct RobotPresence {
  std::string robot, server;
  bool online = false;
  std::string mode;                   // e.g. "TELEOP", "ESTOP"
  std::optional<double> x_m, y_m;
  Time seen{};
};

/// A tuning session of the fuzzy-PID tuner (docs/tuning.md), as one row.
struct TuningSession {
  int64_t rowid = 0;             // tuning_sessions.id (set by the catalog)
  std::string id;                // session_id, unique, e.g. "20261122-083015-tune-robot1"
  Time created{};
  std::string robot;             // the robot it was tuned for; "" = none (NULL)
  std::string reference;         // e.g. "circle r=3.5 m v=0.5 m/s laps=1"
  std::string plant_json = "{}"; // the plant tuned for (per wheel gain, time constant, dead time, saturation)
  std::string params;            // tuned gains, comma list, e.g. "kp,ki,kd,ke,kec,k1,k2,k3"
  std::string algorithm;         // e.g. "GN_CRS2_LM + LN_BOBYQA"
  int64_t evals = 0;
  double wall_s = 0;
  bool cancelled = false;
  double initial_cost = 0, best_cost = 0;  // NaN (stored as NULL): no evaluation finished
  std::string initial_gains_json = "{}", best_gains_json = "{}";
  std::string dir;               // the session directory (summary.md, results.json, ...)
};

/// Gains sent to a robot and its answer.
inline constexpr std::string_view kPushStatuses[] = {"accepted", "rejected"};

struct GainsPush {
  int64_t rowid = 0;             // gains_pushes.id (set by the catalog)
  std::string robot;             // robot id (required; not checked against robots)
  Time time{};
  int64_t version = 0;           // the gains version the robot answered with
  std::string gains_json = "{}"; // the gains pushed
  std::string status;            // one of kPushStatuses
  std::string reason;            // why rejected; "" when accepted
  std::string session_id;        // the tuning session the gains came from; "" = none (NULL)
};

/// The built-in schema migrations, oldest first. PRAGMA user_version is the
/// number applied. Append only: a released migration is never edited.
std::span<const std::string_view> schemaMigrations();

/// A run's id before any suffix: "<UTC start yyyymmdd-hhmmss>-<robot>"
/// (characters of the robot id outside [A-Za-z0-9_.-] become '_').
std::string runIdBase(const std::string& robot, Time start);

/// "2026-11-22T08:30:15.123Z" (UTC, milliseconds).
std::string formatIsoUtc(Time t);
/// Reads "YYYY-MM-DD", "YYYY-MM-DD[T ]HH:MM[:SS[.fff]][Z]" as UTC; none if malformed.
std::optional<Time> parseIsoUtc(std::string_view text);

class Catalog {
 public:
  /// Opens or creates the file (sets WAL, synchronous=NORMAL, foreign keys and
  /// a busy timeout), or connects to the PostgreSQL database of a
  /// "postgresql://" URL, and applies the pending migrations in one
  /// transaction. Throws CatalogError (file missing directory, not a
  /// database, server unreachable, not a catalog, written by a newer
  /// program, ...).
  static Catalog open(const std::string& path);
  /// The same with another migration list (tests: an older schema).
  static Catalog open(const std::string& path, std::span<const std::string_view> migrations);

  Catalog(Catalog&&) noexcept;
  Catalog& operator=(Catalog&&) noexcept;
  ~Catalog();

  /// The file path, or the URL without its password.
  const std::string& path() const;
  int schemaVersion();

  /// This server's id: written on its runs, events and alarms, and
  /// markIncompleteRuns ends only its own runs (and those of no server).
  /// "" (the default) is a catalog that one server keeps.
  void setServerId(const std::string& id);
  const std::string& serverId() const;
  /// Adds the server or updates its row (started is kept from its last start).
  void upsertServer(const ServerInfo& s);
  /// Every server, most recently seen first.
  std::vector<ServerInfo> listServers();
  /// Replaces the robot's presence row.
  void setPresence(const RobotPresence& p);
  /// Every robot's presence, by robot id.
  std::vector<RobotPresence> listPresence();

  /// Adds the robot or updates its software version and last_seen.
  void upsertRobot(const std::string& robot, const std::string& software_version, Time now);

  /// A new run, id runIdBase() with "-2", "-3"... when taken, or r.id. With
  /// r.id: the row of that id when it is this server's run of the robot
  /// started at r.start (written before); throws when another run has it.
  RunInfo startRun(const RunStart& r);
  /// Ends a running run. False if it had already ended (unchanged); throws for
  /// an unknown run or outcome.
  bool endRun(const std::string& run_id, const std::string& outcome, Time end);
  /// Replaces the run's gains in force (JSON); throws for an unknown run.
  void setGains(const std::string& run_id, const std::string& gains_json);
  /// The robot's run that has not ended (the newest), e.g. to carry on after a reconnect.
  std::optional<RunInfo> activeRun(const std::string& robot);
  /// At start-up: every run of this server (or of none) without an end
  /// becomes 'incomplete', its end time the last event or alarm recorded
  /// (else its start). Returns their ids.
  std::vector<std::string> markIncompleteRuns();

  /// run_id "" = not during a run.
  void addEvent(const std::string& run_id, const std::string& robot, Time t, const std::string& kind,
                const std::string& text);
  void addAlarm(const std::string& run_id, const std::string& robot, Time t, const std::string& channel,
                const std::string& level, const std::string& state, double value, double x_m, double y_m);
  /// Replaces the run's summary and gas figures.
  void setSummary(const std::string& run_id, const Summary& s);
  /// Adds the file, or updates its kind and size if the run already lists that path.
  void addFile(const std::string& run_id, const std::string& kind, const std::string& path, int64_t bytes);

  std::vector<RunInfo> listRuns(const RunFilter& f = {});
  /// By run id, or by rowid when `run_id` is all digits.
  std::optional<RunDetail> run(const std::string& run_id);

  /// Records a tuning session; throws for an empty or already recorded id.
  void addTuningSession(const TuningSession& s);
  /// Newest first; `limit` <= 0: all.
  std::vector<TuningSession> listTuningSessions(int limit = 100);
  /// By session id.
  std::optional<TuningSession> tuningSession(const std::string& id);

  /// Records a gains push and the robot's answer; throws for an empty robot or an unknown status.
  void addGainsPush(const GainsPush& p);
  /// Newest first; `robot` "" = every robot; `limit` <= 0: all.
  std::vector<GainsPush> listGainsPushes(const std::string& robot, int limit = 100);

  /// "ok", or the engine's messages one per line.
  std::string integrityCheck();

  /// Writes of a local spool (CatalogSpool) exactly once: in one transaction,
  /// calls `write(i)` for each seqs[i] (ascending) the catalog has not yet
  /// applied for `spool_id`, and records the last seq as applied. Returns how
  /// many it ran (0: all written before). A throw from `write` rolls all back.
  int64_t applySpooled(const std::string& spool_id, std::span<const int64_t> seqs,
                       const std::function<void(std::size_t i)>& write);
  /// The last seq applied for the spool (0: none).
  int64_t spoolApplied(const std::string& spool_id);

 private:
  struct Impl;
  explicit Catalog(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace inspect::catalog
