#pragma once
// The robot link's settings (config/server.yaml top level and "tls:"), loaded by app/server_config.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace inspect::server {

/// Per robot session (token buckets, docs/load.md): what a robot may send.
/// A 100 Hz robot sends ~170 messages and ~60 kB a second.
struct RobotLimits {
  double messages_per_s = 2000;
  double bytes_per_s = 4e6;
  double burst_s = 1.0;          // bucket depth, in seconds of the rate
  double close_after_s = 5.0;    // over the limit this long without a pause of 1 s: disconnected
};

/// Mutual TLS on the robot link (docs/security.md). Relative paths are from the working directory.
struct TlsServerConfig {
  bool plaintext = false;                // only from --plaintext, never from a file
  std::string ca = "certs/ca.pem";       // the CA that signed the robots' certificates
  std::string cert = "certs/server.pem";
  std::string key = "certs/server.key";
};

/// The robots' link: listener and sessions (docs/link-protocol.md).
struct LinkConfig {
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
  TlsServerConfig tls;
};

}  // namespace inspect::server
