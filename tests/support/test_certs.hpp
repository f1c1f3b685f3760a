#pragma once
// Certificates for the tests' TLS links: scripts/make_certs.sh into
// <build>/test_certs (made once, then only missing robot ids are added; the
// script serialises concurrent callers).
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "tests/support/paths.hpp"

namespace inspect::test {

/// The directory with ca.pem, server.pem/.key and <id>.pem/.key for every id asked for.
/// `dir_name` other than "test_certs" makes an unrelated CA (for "wrong CA" tests).
inline std::string testCertsDir(const std::vector<std::string>& robot_ids = {},
                                const std::string& dir_name = "test_certs") {
  const std::string dir = binDir() + "/../" + dir_name;
  std::string cmd = "bash '" + srcPath("scripts/make_certs.sh") + "' --out '" + dir + "'";
  for (const auto& id : robot_ids) cmd += " '" + id + "'";
  cmd += " >/dev/null";
  if (std::system(cmd.c_str()) != 0) throw std::runtime_error("scripts/make_certs.sh failed: " + cmd);
  return dir;
}

}  // namespace inspect::test
