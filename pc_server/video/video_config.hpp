#pragma once
// The video hub's settings (config/server.yaml "video:"), loaded by app/server_config.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace inspect::server {

/// Camera streams (docs/video.md).
struct VideoServerConfig {
  bool enabled = true;
  std::string bind;                      // "" = the link's bind address
  uint16_t port = 5600;                  // UDP; 0 = any free port (tests)
  std::string dir = "video";             // <dir>/<robot>.sdp and snapshots
  uint16_t forward_base_port = 5700;     // RTP re-sent to 127.0.0.1:<base + n> for players; 0 = off
  std::string window = "auto";           // auto (when $DISPLAY is set) | on | off
  double snapshot_period_s = 5.0;        // no window: <dir>/<robot>_latest.png this often; 0 = on request only
  std::size_t reorder_window = 16;       // packets
  double keyframe_min_interval_s = 0.3;
};

}  // namespace inspect::server
