#pragma once
// The recorder's settings (config/server.yaml "recording:"), loaded by app/server_config.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace inspect::server {

/// Recording of runs (docs/recording.md).
struct RecordingServerConfig {
  bool enabled = true;
  std::string dir = "runs";
  bool auto_start = true;
  std::string compression = "zstd";
  double max_fragment_s = 0.5;
  /// The run catalog: "" = <dir>/catalog.sqlite; a SQLite path; or a
  /// "postgresql://" URL a fleet's servers share (docs/catalog.md).
  std::string catalog;
  /// This server in a shared catalog (its runs, events and alarms; which open
  /// runs it ends at start-up); "" = none (a SQLite file is one server's).
  /// Not a key of its own: resolveConfig derives it from the server's
  /// server_id (catalogServerId).
  std::string server_id;
  /// A runs root the fleet's servers share (a network file system): each
  /// ended run is copied to <shared_runs>/<server>/<run-id>/, where another
  /// server's operator reports, exports and replays it; "" = none.
  std::string shared_runs;
};

}  // namespace inspect::server
