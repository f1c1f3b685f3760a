#pragma once
// The catalog's writes, kept in a local spool and written through by one
// thread (docs/catalog.md "When the catalog is away"). A recording server
// queues every write here and goes on at once: the write lands in a local
// SQLite file first (so a crash loses nothing), and the writer applies the
// spool to the catalog in order, in batches, each exactly once
// (Catalog::applySpooled keeps the last seq applied per spool in the same
// transaction). When the catalog cannot be reached (CatalogUnavailable) the
// writes wait in the spool and the writer tries again; a write the catalog
// refuses (CatalogError) is dropped and said, so that one bad write never
// holds the others back.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "shared/catalog/catalog.hpp"

namespace inspect::catalog {

class SqlBackend;

struct SpoolStatus {
  bool reachable = true;
  int64_t pending = 0;        // writes in the spool, not yet in the catalog
  int64_t written = 0;        // written through since the spool opened
  int64_t dropped = 0;        // refused by the catalog (each said in a notice)
  double away_s = 0;          // how long the catalog has been unreachable (0: reachable)
  std::string error;          // why it is unreachable
  // The last time it came back: the writes kept meanwhile and how long
  // writing them through took (from the first successful write to an empty spool).
  int64_t last_backlog = 0;
  double last_catch_up_s = 0;
};

class CatalogSpool {
 public:
  struct Options {
    std::chrono::milliseconds retry_first{200};   // the first retry after the catalog went away
    std::chrono::milliseconds retry_max{2000};    // retries back off to this
    int batch = 200;                              // writes per catalog transaction
    std::chrono::milliseconds close_wait{5000};   // the destructor writes through this long (if reachable)
  };

  /// Opens (creates) the spool file and starts the writer, which first
  /// writes through what an earlier process left in the spool. `catalog`
  /// must outlive the spool. Throws CatalogError when the file cannot be used.
  CatalogSpool(Catalog& catalog, const std::string& path);
  CatalogSpool(Catalog& catalog, const std::string& path, Options options);
  ~CatalogSpool();  // writes through for up to close_wait; the rest stays in the file
  CatalogSpool(const CatalogSpool&) = delete;
  CatalogSpool& operator=(const CatalogSpool&) = delete;

  const std::string& path() const { return path_; }
  /// This spool's id in the catalog's spool_applied (made when the file was created).
  const std::string& id() const { return id_; }

  // The writes (Catalog's of the same name), queued in order. They return at
  // once and throw CatalogError only when the spool file cannot be written.
  void upsertRobot(const std::string& robot, const std::string& software_version, Time now);
  /// r.id must be set (the recorder names its runs; the catalog cannot be asked).
  void startRun(const RunStart& r);
  void endRun(const std::string& run_id, const std::string& outcome, Time end);
  void setGains(const std::string& run_id, const std::string& gains_json);
  void addEvent(const std::string& run_id, const std::string& robot, Time t, const std::string& kind,
                const std::string& text);
  void addAlarm(const std::string& run_id, const std::string& robot, Time t, const std::string& channel,
                const std::string& level, const std::string& state, double value, double x_m, double y_m);
  void setSummary(const std::string& run_id, const Summary& s);
  void addFile(const std::string& run_id, const std::string& kind, const std::string& path, int64_t bytes);

  /// A server's row and a robot's presence: only the latest of each is worth
  /// writing, so they are kept in memory (not spooled) and written when the
  /// catalog is there; one newer replaces one not yet written.
  void upsertServer(const ServerInfo& s);
  void setPresence(const RobotPresence& p);

  /// Waits until every write queued before the call (and the latest server
  /// and presence rows) is in the catalog, for at most `timeout`; false when
  /// some are not (the catalog away).
  bool flush(std::chrono::milliseconds timeout);
  SpoolStatus status() const;
  /// The notices after `cursor` (0 at first), which it advances: the catalog
  /// went away, came back (with the writes and time to catch up), refused a write.
  std::vector<std::string> noticesSince(uint64_t& cursor) const;

 private:
  struct Pending;
  void queue(const std::string& op);
  void writerLoop();
  /// One batch from the spool into the catalog; false when the spool was empty.
  bool writeBatch(int limit);
  /// The latest server and presence rows into the catalog.
  void writeLatest();
  void apply(const std::string& op);
  void notice(std::string text);
  void wentAway(const std::string& why);
  // Under mu_, after a write went through: the first after an outage (the
  // attempt began at attempt_ with attempt_pending_ writes kept), and the
  // spool emptied after one.
  void wroteLocked();
  void cameBackLocked();
  void caughtUpLocked();

  Catalog& catalog_;
  std::string path_, id_;
  Options options_;
  std::unique_ptr<SqlBackend> file_;  // the spool file, under file_mu_
  std::mutex file_mu_;

  mutable std::mutex mu_;  // what follows
  std::condition_variable cv_;
  int64_t queued_seq_ = 0;   // the newest write queued
  int64_t done_seq_ = 0;     // every write up to this is in the catalog (or dropped)
  bool stop_ = false;
  SpoolStatus status_;
  std::optional<std::chrono::steady_clock::time_point> away_since_, catching_up_since_;
  int64_t backlog_ = 0;  // writes kept when it came back
  double away_s_ = 0;    // how long it was away, the last time
  std::chrono::steady_clock::time_point attempt_;  // the writer's current attempt began
  int64_t attempt_pending_ = 0;                    // with this many writes kept
  std::vector<std::string> notices_;
  std::optional<ServerInfo> server_latest_;
  std::map<std::string, RobotPresence> presence_latest_;  // by robot
  uint64_t latest_queued_ = 0, latest_done_ = 0;  // generations of the latest rows
  std::thread writer_;
};

}  // namespace inspect::catalog
