#include "pc_server/sparkplug/sparkplug_credentials.hpp"

#include <sys/stat.h>

#include <cstdio>

#include "shared/config/config_node.hpp"
#include "shared/util/log.hpp"

namespace inspect::server::sparkplug {

Credentials loadCredentials(const std::string& path) {
  const auto root = config::ConfigNode::loadFile(path);
  Credentials c;
  c.username = root.string("username", "");
  if (c.username.empty()) root.fail("username", "must not be empty");
  c.password = root.string("password", "");
  root.checkKnown();
  struct stat st{};
  // Others than the owner and the group (the service's: root:inspect 0640 is the packaged way).
  if (::stat(path.c_str(), &st) == 0 && (st.st_mode & 007) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%03o", static_cast<unsigned>(st.st_mode & 0777));
    log::warn("sparkplug", path, " has mode ", mode, ": any user may read the broker's password; chmod o-rwx it");
  }
  return c;
}

}  // namespace inspect::server::sparkplug
