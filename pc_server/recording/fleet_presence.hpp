#pragma once
// What a fleet sees of this server in a shared catalog (docs/catalog.md,
// `robots --fleet`): the server's row (where to attach to it) and each of
// its robots' presence (online, mode, where), written every kPresencePeriod
// and once more, all offline, when the server stops.
#include <chrono>
#include <string>
#include <vector>

#include "pc_server/link/robot_registry.hpp"
#include "shared/catalog/catalog.hpp"

namespace inspect::server {

/// How often a server writes its row and its robots' presence.
inline constexpr std::chrono::seconds kPresencePeriod{2};
/// A server not seen for this long is gone (killed, cut off): `robots
/// --fleet` does not show its robots online.
inline constexpr std::chrono::seconds kPresenceStale{10};

/// The presence rows of `robots` (the registry's snapshots) held by `server` at `now`.
std::vector<catalog::RobotPresence> presenceOf(const std::vector<RobotSnapshot>& robots, const std::string& server,
                                               catalog::Time now);

/// `robots --fleet`: one line a robot, with its server and where to attach to
/// it; a robot whose server has not been seen for kPresenceStale is not online.
std::string fleetTable(const std::vector<catalog::RobotPresence>& presence,
                       const std::vector<catalog::ServerInfo>& servers, catalog::Time now);

}  // namespace inspect::server
