#pragma once
// Recording of inspection runs on the server (docs/recording.md): per robot
// at most one run, written to <dir>/<run-id>/ as run.mcap (every telemetry
// message, command, ack and event on its own channel, and the camera's H.264
// frames as foxglove.CompressedVideo) and video.mp4 (fragmented, no
// re-encode), listed in <dir>/catalog.sqlite with its summary figures.
// A run survives robot reconnects (marked in the log). At start-up, runs a
// killed server left open are marked incomplete and their MCAP files repaired.
// The catalog's writes go through a local spool (<dir>/catalog-spool.sqlite,
// shared/catalog/catalog_spool.hpp): recording never waits for the catalog,
// and goes on while a shared catalog is away. Thread-safe.
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "inspect_robot/v1/link.pb.h"
#include "pc_server/recording/run_copier.hpp"
#include "pc_server/recording/run_stats.hpp"
#include "pc_server/scene/robot_scene.hpp"
#include "pc_server/scene/site_maps.hpp"
#include "pc_server/recording/recording_config.hpp"
#include "shared/catalog/catalog.hpp"
#include "shared/catalog/catalog_spool.hpp"
#include "shared/video/rtp_h264.hpp"

namespace inspect::server {

using RecordingConfig = RecordingServerConfig;

/// Video figures of a robot's stream, for the run summary.
struct VideoFigures {
  int64_t frames_received = 0, frames_decoded = 0, packets_lost = 0;
};

/// The wheel PID gains a telemetry message reports while tracking, as JSON
/// ({"controller":"fuzzy_pid","kp":..,"ki":..,"kd":..}); "{}" when not tracking.
std::string gainsJson(const v1::Telemetry& t);
/// The full gain set a robot announced (Hello, GAINS_APPLIED) with its version, as JSON.
std::string runGainsJson(const v1::Gains& g, uint32_t version);

class Recorder {
 public:
  /// Opens (creates) <dir>/catalog.sqlite, marks runs left open as
  /// incomplete and repairs their MCAP files. Throws std::runtime_error.
  Recorder(const RecordingConfig& config, std::string software_version);
  ~Recorder();  // ends open runs as "stopped"

  /// Starts a run for `robot`; returns its id. Throws std::runtime_error
  /// (already recording, cannot create files).
  std::string start(const std::string& robot, const std::string& name, const std::string& route = "");
  /// Ends the robot's run; its id, or nullopt when none was recording.
  std::optional<std::string> stop(const std::string& robot, const std::string& outcome = "stopped");
  std::optional<std::string> activeRun(const std::string& robot) const;

  /// Every envelope to or from a robot (LinkServer's observer).
  void onEnvelope(const std::string& robot, const std::string& address, const v1::Envelope& env, bool inbound,
                  uint64_t time_us);
  /// Every intact access unit of a robot's camera head (VideoReceiver's
  /// hook): the PTZ head's into run.mcap's /<robot>/camera and video.mp4,
  /// the wide head's into /<robot>/camera_wide.
  void onAccessUnit(const std::string& robot, v1::CameraHead head, const video::Frame& frame, uint64_t capture_us);
  /// Closes MCAP chunks of quiet recordings; call every 100-200 ms.
  void tick();
  /// Where a new run gets the robot's controller gains in force (JSON; "{}" when unknown).
  void setGainsSource(std::function<std::string(const std::string& robot)> f);
  /// Where run summaries get the robot's video figures.
  void setVideoFigures(std::function<std::optional<VideoFigures>(const std::string& robot)> f);
  /// Where a run gets the robot's Hello (gas channel names and units), written
  /// to the run's /robot_info channel at its start.
  void setHelloSource(std::function<std::optional<v1::Hello>(const std::string& robot)> f);
  /// The site map (world file) of the robot's current run, or of its next one
  /// when none is running (`inspect` with a route that names a map); listed
  /// as the run's "map" file, which reports draw. "" forgets a pending one.
  void setRunMap(const std::string& robot, const std::string& map_path);
  /// Every run also records the robot's 3-D scene (docs/mcap.md: /tf, /scene,
  /// /gas/<channel>, /log), drawn with this geometry on the map `maps` gives
  /// (null: no map). Set before the first run.
  void setScene(scene::SiteMaps* maps, const scene::Geometry& geometry);
  /// The operator acknowledged a gas alarm: /server_event and the catalog's alarms.
  void noteAlarmAck(const std::string& robot, const v1::GasAlarm& alarm, const std::string& text);

  /// The catalog to read, with every write queued so far in it (waits up to
  /// 5 s for the spool, not at all while the catalog is away).
  catalog::Catalog& catalog();
  /// The spool's state: reachable, writes kept, written, dropped.
  catalog::SpoolStatus catalogStatus() const { return spool_->status(); }
  /// This server's row and its robots' presence in a shared catalog
  /// (fleet_presence.hpp): written when the catalog is there, latest only.
  void notePresence(const catalog::ServerInfo& server, const std::vector<catalog::RobotPresence>& robots);
  /// The catalog's notices after `cursor` (away, back, a refused write); advances it.
  std::vector<std::string> catalogNotices(uint64_t& cursor) const { return spool_->noticesSince(cursor); }
  const RecordingConfig& config() const { return config_; }
  /// Where the fleet finds this server's runs: <shared_runs>/<server> when
  /// configured, else its own runs directory (absolute).
  std::string runsRoot() const;
  /// The directory of a run's files as this server reaches it: its own runs
  /// directory, or another server's run in the shared runs root; "" and
  /// `why` when it cannot.
  std::string runDir(const catalog::RunInfo& run, std::string* why = nullptr) const;
  /// Waits up to `timeout_s` for the copies to the shared runs root; false if some are not done.
  bool waitForCopies(double timeout_s) { return !copier_ || copier_->waitIdle(timeout_s); }
  /// What start-up found: "2 runs marked incomplete (…), MCAP repaired: …".
  const std::string& startupReport() const { return startup_report_; }

 private:
  struct Run;
  std::string startLocked(const std::string& robot, const std::string& name, const std::string& route,
                          uint64_t command_id);
  std::string stopLocked(const std::string& robot, const std::string& outcome);
  /// A server note in the run: /server_event and the catalog (`kind`), at
  /// `wall_ns` (0 = now).
  void noteLocked(Run& r, const std::string& robot, const std::string& text, const std::string& kind = "server",
                  uint64_t wall_ns = 0);
  /// A run started by a command the server sends (config auto_start): track, go-to, a wheel test.
  void autoStartLocked(const std::string& robot, const v1::Command& c);
  /// A gas alarm goes into the catalog whether or not a run records it (run_id "" = none).
  void catalogAlarmLocked(const std::string& robot, const v1::Envelope& env, bool inbound,
                               const std::string& run_id, catalog::Time when);
  void recordTelemetryLocked(Run& r, const std::string& robot, const v1::Envelope& env, uint64_t time_us,
                             uint64_t log_ns);
  void recordEventLocked(Run& r, const std::string& robot, const v1::Envelope& env, uint64_t publish_ns,
                         uint64_t log_ns, catalog::Time when);
  /// A stored event or ack the robot sent late (store-and-forward).
  static bool isLate(const v1::Envelope& env);
  /// The id of the robot's run recording at `t` (runs this process ended,
  /// else the catalog), "" = none.
  std::string runAt(const std::string& robot, catalog::Time t);
  /// A run id not used yet: runIdBase, with "-2", "-3"... when its directory exists.
  std::string newRunId(const std::string& robot, catalog::Time start) const;
  /// Telemetry absent this long within a run is marked as a gap.
  static constexpr uint64_t kTelemetryGapNs = 1'000'000'000;

  RecordingConfig config_;
  std::string software_version_;
  std::unique_ptr<catalog::Catalog> catalog_;
  std::unique_ptr<catalog::CatalogSpool> spool_;  // every write to catalog_ (destroyed first)
  struct RunSpan {
    std::string id;
    catalog::Time start, end;
  };
  std::map<std::string, std::vector<RunSpan>> ended_;  // robot -> its latest runs ended here, newest last
  /// <shared_runs>/<server ("local" when none)>/<run id>.
  std::string sharedDir(const std::string& server, const std::string& run_id) const;
  /// At start-up: every run of this server's directory without a shared copy.
  void queueUncopiedRuns();
  std::unique_ptr<RunCopier> copier_;  // ended runs to the shared runs root (null: none); uses spool_
  std::string startup_report_;
  std::function<std::optional<VideoFigures>(const std::string&)> video_figures_;
  std::function<std::string(const std::string&)> gains_source_;
  std::function<std::optional<v1::Hello>(const std::string&)> hello_source_;
  void writeScene(Run& r, const std::string& robot, uint64_t ns, bool telemetry);
  /// The run's wide-head channels (camera, people), made at the first use.
  static std::pair<uint16_t, uint16_t> wideChannels(Run& r);
  scene::SiteMaps* site_maps_ = nullptr;
  scene::Geometry geometry_;
  std::map<std::string, std::string> pending_map_;  // robot -> map for its next run
  std::map<std::string, v1::Hello> hello_;          // robot -> Hello at its run's start
  mutable std::mutex mu_;
  std::map<std::string, std::unique_ptr<Run>> runs_;  // robot -> its run
};

}  // namespace inspect::server
