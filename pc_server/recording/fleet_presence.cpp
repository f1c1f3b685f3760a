#include "pc_server/recording/fleet_presence.hpp"

#include <map>

#include "shared/util/number_text.hpp"

namespace inspect::server {

using util::fmtFixed;
using util::padRight;

std::vector<catalog::RobotPresence> presenceOf(const std::vector<RobotSnapshot>& robots, const std::string& server,
                                               catalog::Time now) {
  std::vector<catalog::RobotPresence> out;
  for (const auto& r : robots) {
    catalog::RobotPresence p;
    p.robot = r.id;
    p.server = server;
    p.online = r.connected;
    p.seen = now;
    if (r.has_telemetry) {
      const auto mode = r.telemetry.mode();
      p.mode = v1::Mode_IsValid(mode) && mode != v1::MODE_UNSPECIFIED ? v1::Mode_Name(mode) : "";
      p.x_m = r.telemetry.pose().x_m();
      p.y_m = r.telemetry.pose().y_m();
    }
    out.push_back(std::move(p));
  }
  return out;
}

std::string fleetTable(const std::vector<catalog::RobotPresence>& presence,
                       const std::vector<catalog::ServerInfo>& servers, catalog::Time now) {
  if (presence.empty()) return "no robot in the fleet's catalog yet\n";
  std::map<std::string, const catalog::ServerInfo*> by_id;
  for (const auto& s : servers) by_id[s.id] = &s;
  const auto ago = [&](catalog::Time t) { return std::chrono::duration<double>(now - t).count(); };
  std::string out = padRight("robot", 16) + " " + padRight("state", 24) + " " + padRight("mode", 10) + " " +
                    padRight("where (m)", 16) + " " + padRight("server", 12) + " attach\n";
  for (const auto& p : presence) {
    const auto sv = by_id.find(p.server);
    const double server_age = sv == by_id.end() ? 1e9 : ago(sv->second->seen);
    std::string state = p.online ? "online" : "offline";
    if (p.online && server_age > std::chrono::duration<double>(kPresenceStale).count())
      state = sv == by_id.end() ? "unknown (no server row)"
                                : "unknown (server silent " + fmtFixed(server_age, 0) + " s)";
    const std::string where =
        p.x_m && p.y_m ? "(" + fmtFixed(*p.x_m, 2) + ", " + fmtFixed(*p.y_m, 2) + ")" : "-";
    out += padRight(p.robot, 16) + " " + padRight(state, 24) + " " + padRight(p.mode.empty() ? "-" : p.mode, 10) +
           " " + padRight(where, 16) + " " + padRight(p.server, 12) + " " +
           (sv == by_id.end() || sv->second->attach.empty() ? "-" : sv->second->attach) + "\n";
  }
  return out;
}

}  // namespace inspect::server
