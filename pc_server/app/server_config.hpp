#pragma once
// pc_server settings (config/server.yaml) and their loader.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "shared/config/config_node.hpp"

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

/// Recording of runs (docs/recording.md).
struct RecordingServerConfig {
  bool enabled = true;
  std::string dir = "runs";
  bool auto_start = true;
  std::string compression = "zstd";
  double max_fragment_s = 0.5;
};

/// Mutual TLS on the robot link (docs/security.md). Relative paths are from the working directory.
struct TlsServerConfig {
  bool plaintext = false;                // only from --plaintext, never from a file
  std::string ca = "certs/ca.pem";       // the CA that signed the robots' certificates
  std::string cert = "certs/server.pem";
  std::string key = "certs/server.key";
};

/// The Foxglove WebSocket bridge (docs/foxglove.md).
struct FoxgloveServerConfig {
  bool enabled = true;
  std::string bind = "127.0.0.1";          // this machine only; another address lets other hosts in (with the token)
  uint16_t port = 8765;                    // the protocol's usual port; 0 = any free port (tests)
  std::string auth = "token";              // token | none (none only with a loopback bind)
  std::string token_file = "foxglove.token";  // read if it exists, else a new random token is written (mode 0600)
  bool tls = false;                        // wss:// with the server's certificate (tls.cert, tls.key)
  std::vector<std::string> allowed_origins;  // browsers' Origin header must be one of these; empty = any
  double scene_hz = 10;                    // SceneUpdate rate per robot, Hz
  double grid_hz = 1;                      // gas grids per robot and channel, Hz
  double teleop_timeout_s = 0.3;           // a client's teleop set-point not renewed this long lapses to zero
  int max_clients = 32;
};

/// Per robot session (token buckets, docs/load.md): what a robot may send.
/// A 100 Hz robot sends ~170 messages and ~60 kB a second.
struct RobotLimits {
  double messages_per_s = 2000;
  double bytes_per_s = 4e6;
  double burst_s = 1.0;          // bucket depth, in seconds of the rate
  double close_after_s = 5.0;    // over the limit this long without a pause of 1 s: disconnected
};

/// Link and console settings; defaults are those documented in config/server.yaml.
struct ServerConfig {
  std::string bind_address = "0.0.0.0";  // all interfaces: robots connect from the network
  uint16_t port = 7600;                  // 0 = ephemeral (tests)
  std::string server_id = "pc_server";
  double heartbeat_period_s = 0.05;
  double session_timeout_s = 1.0;
  double telemetry_stale_s = 0.25;       // a moving robot whose telemetry stops this long is e-stopped; 0 = never
  double handshake_timeout_s = 5.0;
  double teleop_resend_hz = 20.0;
  std::size_t max_frame_bytes = 1u << 20;
  RobotLimits robot_limits;
  double status_refresh_hz = 5.0;
  VideoServerConfig video;
  RecordingServerConfig recording;
  TlsServerConfig tls;
  std::string operator_socket;           // Unix socket for more operator consoles; "" = none
  FoxgloveServerConfig foxglove;
  std::string site_map;                  // world file drawn in every robot's 3-D scene ("" = none; routes' maps win)
};

/// True for a numeric IPv4/IPv6 address.
bool validBindAddress(const std::string& address);

/// Reads and validates a server config. Throws config::ConfigError naming file and key.
ServerConfig loadServerConfig(const config::ConfigNode& root);
/// loadServerConfig + checkKnown on a file.
ServerConfig loadServerConfigFile(const std::string& path);

}  // namespace inspect::server
