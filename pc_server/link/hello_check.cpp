#include "pc_server/link/hello_check.hpp"

#include <algorithm>

#include "shared/net/link_version.hpp"
#include "shared/net/robot_id.hpp"

namespace inspect::server {

std::optional<std::string> helloRejection(const v1::Hello& hello) {
  if (hello.protocol_version() != net::kProtocolVersion) {
    const uint32_t v = hello.protocol_version();
    std::string why = "protocol version mismatch: robot speaks " + std::to_string(v) + ", server speaks " +
                      std::to_string(net::kProtocolVersion);
    if (v < net::kProtocolVersion)
      why += "; update the robot (robot_client, or code generated from this server's proto/): version 2 gave "
             "Telemetry fields explicit presence (docs/link-protocol.md, Versions)";
    else
      why += "; update the server to the robot's version (docs/link-protocol.md, Versions)";
    return why;
  }
  if (!net::validRobotId(hello.robot_id())) {
    std::string shown = hello.robot_id().substr(0, 80);
    std::replace_if(shown.begin(), shown.end(), [](char c) { return c < 0x20 || c > 0x7e; }, '?');
    return "invalid robot id '" + shown + "' (must be 1-64 characters of A-Z a-z 0-9 _ -)";
  }
  return std::nullopt;
}

}  // namespace inspect::server
