#pragma once
// pc_server settings (config/server.yaml) and their loader.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "pc_server/foxglove/foxglove_config.hpp"
#include "pc_server/link/link_config.hpp"
#include "pc_server/recording/recording_config.hpp"
#include "pc_server/sparkplug/sparkplug_config.hpp"
#include "pc_server/video/video_config.hpp"
#include "shared/config/config_node.hpp"

namespace inspect::server {

/// Link and console settings; defaults are those documented in config/server.yaml.
/// The link's own settings are the base (link/link_config.hpp), so cfg.port reads as before.
struct ServerConfig : LinkConfig {
  double status_refresh_hz = 5.0;
  VideoServerConfig video;
  RecordingServerConfig recording;
  std::string operator_socket;           // Unix socket for more operator consoles; "" = none
  FoxgloveServerConfig foxglove;
  std::string site_map;                  // world file drawn in every robot's 3-D scene ("" = none; routes' maps win)
  sparkplug::SparkplugConfig sparkplug;  // the MQTT Sparkplug B edge node (docs/sparkplug.md); off by default
};

/// True for a numeric IPv4/IPv6 address.
bool validBindAddress(const std::string& address);

/// Reads and validates a server config. Throws config::ConfigError naming file and key.
ServerConfig loadServerConfig(const config::ConfigNode& root);
/// loadServerConfig + checkKnown on a file.
ServerConfig loadServerConfigFile(const std::string& path);

}  // namespace inspect::server
