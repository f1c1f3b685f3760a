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
};

}  // namespace inspect::server
