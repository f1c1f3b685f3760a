#pragma once
// The services a Foxglove client may call (docs/foxglove.md, "Services"):
// each is a console command with JSON arguments, run in the client's own
// operator session with the console's rules (control, limits, acks). Pure:
// JSON in, the console line out.
#include <string>
#include <string_view>
#include <vector>

#include "pc_server/foxglove/ws_protocol.hpp"

namespace inspect::server::foxglove {

struct ServiceDef {
  std::string name;            // e.g. "/goto"
  std::string type;            // e.g. "inspect/GoTo"
  std::string request_schema;  // JSON Schema
  std::string summary;
};
/// Every service, in the order advertised; all answer {"ok": bool, "message": string}.
const std::vector<ServiceDef>& serviceDefs();
/// The JSON Schema of every response.
const std::string& responseSchema();
/// The advertised form of a definition (id left 0).
Service toService(const ServiceDef& d);

/// A request turned into what the session runs: an optional robot to select
/// first, then one console line; or what was wrong with the request.
struct ServiceRequest {
  std::string robot;  // "" = the session's selected robot
  std::string line;   // e.g. "goto 1.5 2 0.3"
  bool immediate = false;  // stop and e-stop: sent at once, never queued behind another call
  std::string error;
  bool ok() const { return error.empty(); }
};
ServiceRequest parseServiceRequest(const std::string& service, std::string_view json);

/// The response payload.
std::string serviceResponse(bool ok, const std::string& message);

}  // namespace inspect::server::foxglove
