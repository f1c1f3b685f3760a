#pragma once
// pc_server command line.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "shared/util/cli_args.hpp"

namespace inspect::server {

/// A bad command line (the one error type of every program's command line).
using cli::UsageError;

/// Parsed command line; unset optionals mean "use the config file / default".
struct CliOptions {
  std::optional<std::string> config_path;
  std::optional<std::string> bind_address;
  std::optional<uint16_t> port;
  std::optional<std::string> port_file;
  std::optional<std::string> script_path;
  std::optional<uint16_t> video_port;
  std::optional<std::string> video_dir;
  std::optional<std::string> video_port_file;
  bool no_video = false;
  std::optional<std::string> runs_dir;
  bool no_record = false;
  std::optional<std::string> catalog;    // --catalog (a URL without a password)
  std::optional<std::string> shared_runs;  // --shared-runs
  std::optional<std::string> server_id;
  std::optional<std::string> certs_dir;  // --certs DIR: DIR/ca.pem, DIR/server.pem, DIR/server.key
  bool plaintext = false;
  bool no_foxglove = false;
  std::optional<uint16_t> foxglove_port;
  std::optional<std::string> foxglove_port_file;
  std::optional<std::string> foxglove_token_file;
  std::optional<std::string> site_map;
  std::optional<std::string> sparkplug_broker;  // --sparkplug-broker HOST:PORT: the edge node on
  std::optional<std::string> operator_socket;  // more operator consoles on this Unix socket
  std::optional<std::string> attach;           // --attach PATH: be a console of a running server
  bool interactive = false;
  bool no_console = false;
  bool help = false;
};

/// Parses argv (without argv[0]). Throws UsageError naming the flag.
CliOptions parseCli(const std::vector<std::string>& args);

/// The --help text.
std::string usageText();

}  // namespace inspect::server
