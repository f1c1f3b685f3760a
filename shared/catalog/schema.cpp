// The run catalog's schema: its migrations, oldest first (docs/catalog.md).
// PRAGMA user_version is the number applied; a migration is never edited once
// released, only appended.
#include "shared/catalog/catalog.hpp"

namespace inspect::catalog {
namespace {

// Version n of the schema is the first n scripts. Append only.
constexpr std::string_view kMigrations[] = {
    // 1: robots, runs, events, alarms.
    R"sql(
CREATE TABLE robots (
  id               TEXT PRIMARY KEY,
  software_version TEXT NOT NULL DEFAULT '',
  first_seen       TEXT NOT NULL,
  first_seen_unix  REAL NOT NULL,
  last_seen        TEXT NOT NULL,
  last_seen_unix   REAL NOT NULL
);
CREATE TABLE runs (
  id               INTEGER PRIMARY KEY,
  run_id           TEXT NOT NULL UNIQUE,
  robot_id         TEXT NOT NULL REFERENCES robots(id),
  name             TEXT NOT NULL DEFAULT '',
  route            TEXT NOT NULL DEFAULT '',
  gains_json       TEXT NOT NULL DEFAULT '{}',
  software_version TEXT NOT NULL DEFAULT '',
  dir              TEXT NOT NULL DEFAULT '',
  start_time       TEXT NOT NULL,
  start_unix       REAL NOT NULL,
  end_time         TEXT,
  end_unix         REAL,
  outcome          TEXT CHECK (outcome IN ('completed', 'stopped', 'failed', 'incomplete')),
  CHECK ((end_time IS NULL) = (outcome IS NULL))
);
CREATE INDEX runs_by_start ON runs(start_unix);
CREATE INDEX runs_by_robot ON runs(robot_id, start_unix);
CREATE TABLE events (
  id        INTEGER PRIMARY KEY,
  run_id    TEXT REFERENCES runs(run_id) ON DELETE CASCADE,
  robot_id  TEXT NOT NULL DEFAULT '',
  time      TEXT NOT NULL,
  time_unix REAL NOT NULL,
  kind      TEXT NOT NULL,
  text      TEXT NOT NULL DEFAULT ''
);
CREATE INDEX events_by_run ON events(run_id, time_unix);
CREATE TABLE alarms (
  id        INTEGER PRIMARY KEY,
  run_id    TEXT REFERENCES runs(run_id) ON DELETE CASCADE,
  robot_id  TEXT NOT NULL DEFAULT '',
  time      TEXT NOT NULL,
  time_unix REAL NOT NULL,
  channel   TEXT NOT NULL,
  level     TEXT NOT NULL,
  state     TEXT NOT NULL,
  value     REAL,
  x_m       REAL,
  y_m       REAL
);
CREATE INDEX alarms_by_run ON alarms(run_id, time_unix);
)sql",
    // 2: per-run summary figures, gas figures, files.
    R"sql(
CREATE TABLE run_summary (
  run_id                  TEXT PRIMARY KEY REFERENCES runs(run_id) ON DELETE CASCADE,
  duration_s              REAL NOT NULL,
  distance_m              REAL NOT NULL,
  min_person_m            REAL,
  track_max_pos_err_m     REAL,
  track_rms_pos_err_m     REAL,
  track_max_angle_err_rad REAL,
  video_frames_received   INTEGER NOT NULL DEFAULT 0,
  video_frames_decoded    INTEGER NOT NULL DEFAULT 0,
  video_packets_lost      INTEGER NOT NULL DEFAULT 0
);
CREATE TABLE run_gas (
  run_id  TEXT NOT NULL REFERENCES runs(run_id) ON DELETE CASCADE,
  channel TEXT NOT NULL,
  unit    TEXT NOT NULL DEFAULT '',
  max     REAL NOT NULL,
  mean    REAL NOT NULL,
  PRIMARY KEY (run_id, channel)
);
CREATE TABLE run_files (
  id     INTEGER PRIMARY KEY,
  run_id TEXT NOT NULL REFERENCES runs(run_id) ON DELETE CASCADE,
  kind   TEXT NOT NULL,
  path   TEXT NOT NULL,
  bytes  INTEGER NOT NULL,
  UNIQUE (run_id, path)
);
)sql",
    // 3: one row a run for the sqlite3 shell.
    R"sql(
CREATE VIEW run_overview AS
SELECT r.id, r.run_id, r.robot_id, r.name, r.route, r.start_time, r.end_time,
       COALESCE(r.outcome, 'running') AS outcome,
       s.duration_s, s.distance_m, s.min_person_m,
       (SELECT count(*) FROM events e WHERE e.run_id = r.run_id) AS events,
       (SELECT count(*) FROM alarms a WHERE a.run_id = r.run_id) AS alarms
FROM runs r LEFT JOIN run_summary s ON s.run_id = r.run_id;
)sql",
    // 4: fuzzy-PID tuning sessions and gains pushed to robots.
    R"sql(
CREATE TABLE tuning_sessions (
  id                 INTEGER PRIMARY KEY,
  session_id         TEXT NOT NULL UNIQUE,
  created_time       TEXT NOT NULL,
  created_unix       REAL NOT NULL,
  robot_id           TEXT,
  reference          TEXT NOT NULL DEFAULT '',
  plant_json         TEXT NOT NULL DEFAULT '{}',
  params             TEXT NOT NULL DEFAULT '',
  algorithm          TEXT NOT NULL DEFAULT '',
  evals              INTEGER NOT NULL DEFAULT 0,
  wall_s             REAL NOT NULL DEFAULT 0,
  cancelled          INTEGER NOT NULL DEFAULT 0 CHECK (cancelled IN (0, 1)),
  initial_cost       REAL,
  best_cost          REAL,
  initial_gains_json TEXT NOT NULL DEFAULT '{}',
  best_gains_json    TEXT NOT NULL DEFAULT '{}',
  dir                TEXT NOT NULL DEFAULT ''
);
CREATE INDEX tuning_sessions_by_created ON tuning_sessions(created_unix);
CREATE TABLE gains_pushes (
  id         INTEGER PRIMARY KEY,
  robot_id   TEXT NOT NULL,
  time       TEXT NOT NULL,
  time_unix  REAL NOT NULL,
  version    INTEGER NOT NULL,
  gains_json TEXT NOT NULL DEFAULT '{}',
  status     TEXT NOT NULL CHECK (status IN ('accepted', 'rejected')),
  reason     TEXT NOT NULL DEFAULT '',
  session_id TEXT
);
CREATE INDEX gains_pushes_by_robot ON gains_pushes(robot_id, time_unix);
)sql",
    // 5: a fleet's servers sharing one catalog: who recorded what, which
    // servers there are, and where each robot is online (docs/catalog.md).
    R"sql(
ALTER TABLE runs ADD COLUMN server_id TEXT NOT NULL DEFAULT '';
ALTER TABLE events ADD COLUMN server_id TEXT NOT NULL DEFAULT '';
ALTER TABLE alarms ADD COLUMN server_id TEXT NOT NULL DEFAULT '';
CREATE INDEX runs_by_server ON runs(server_id, start_unix);
CREATE TABLE servers (
  id           TEXT PRIMARY KEY,
  attach       TEXT NOT NULL DEFAULT '',
  runs_root    TEXT NOT NULL DEFAULT '',
  software_version TEXT NOT NULL DEFAULT '',
  started_time TEXT NOT NULL,
  started_unix REAL NOT NULL,
  seen_time    TEXT NOT NULL,
  seen_unix    REAL NOT NULL
);
CREATE TABLE robot_presence (
  robot_id  TEXT PRIMARY KEY,
  server_id TEXT NOT NULL,
  online    INTEGER NOT NULL CHECK (online IN (0, 1)),
  mode      TEXT NOT NULL DEFAULT '',
  x_m       REAL,
  y_m       REAL,
  seen_time TEXT NOT NULL,
  seen_unix REAL NOT NULL
);
)sql",
    // 6: exactly-once writes from each server's local spool, kept while the
    // catalog was away (CatalogSpool): the last write applied per spool.
    R"sql(
CREATE TABLE spool_applied (
  spool_id  TEXT PRIMARY KEY,
  server_id TEXT NOT NULL DEFAULT '',
  seq       INTEGER NOT NULL,
  time      TEXT NOT NULL,
  time_unix REAL NOT NULL
);
)sql",
};

}  // namespace

std::span<const std::string_view> schemaMigrations() { return kMigrations; }

}  // namespace inspect::catalog
