#pragma once
// The Foxglove bridge's settings (config/server.yaml "foxglove:"), loaded by app/server_config.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace inspect::server {

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

}  // namespace inspect::server
