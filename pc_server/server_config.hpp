#pragma once
// pc_server settings (config/server.yaml) and their loader.
#include <cstddef>
#include <cstdint>
#include <string>

#include "shared/config/config_node.hpp"

namespace inspect::server {

/// Link and console settings; defaults are those documented in config/server.yaml.
struct ServerConfig {
  std::string bind_address = "0.0.0.0";  // all interfaces: robots connect from the network
  uint16_t port = 7600;                  // 0 = ephemeral (tests)
  std::string server_id = "pc_server";
  double heartbeat_period_s = 0.1;
  double session_timeout_s = 1.0;
  double handshake_timeout_s = 5.0;
  double teleop_resend_hz = 20.0;
  std::size_t max_frame_bytes = 1u << 20;
  double status_refresh_hz = 5.0;
};

/// True for a numeric IPv4/IPv6 address.
bool validBindAddress(const std::string& address);

/// Reads and validates a server config. Throws config::ConfigError naming file and key.
ServerConfig loadServerConfig(const config::ConfigNode& root);
/// loadServerConfig + checkKnown on a file.
ServerConfig loadServerConfigFile(const std::string& path);

}  // namespace inspect::server
