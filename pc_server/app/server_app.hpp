#pragma once
// The pc_server program: config + CLI -> io_context (2 threads), link server,
// signal handling and the console in the chosen mode.
#include "pc_server/app/cli_options.hpp"
#include "pc_server/app/server_config.hpp"

namespace inspect::server {

/// Loads the config named by the CLI (or config/server.yaml if present) and applies overrides.
/// Throws config::ConfigError.
ServerConfig resolveConfig(const CliOptions& options);
/// The server's id in its catalog: none with a SQLite file; with a
/// PostgreSQL one its server_id, or the host name when that is the default
/// (every server would share "pc_server").
std::string catalogServerId(const ServerConfig& c);

/// Writes `port` to `path` through a temporary file and a rename. Throws util::StartupError.
void writePortFile(const std::string& path, uint16_t port, const std::string& flag = "--port-file");

/// Runs the server until the console ends or SIGINT/SIGTERM; returns the exit status.
/// Throws config::ConfigError / util::StartupError for startup failures.
int runServer(const CliOptions& options);

}  // namespace inspect::server
