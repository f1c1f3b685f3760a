#pragma once
// The broker's user name and password (server.yaml sparkplug.credentials_file;
// docs/sparkplug.md): a YAML file of `username:` and `password:`, read at
// start. Never from the command line, which `ps` shows to every user.
#include <string>

namespace inspect::server::sparkplug {

struct Credentials {
  std::string username, password;
};

/// Reads `path`; throws config::ConfigError naming the file and the key
/// (missing username, unknown key). Warns when any user may read the file.
Credentials loadCredentials(const std::string& path);

}  // namespace inspect::server::sparkplug
