#pragma once
// The services a Foxglove client may call (docs/foxglove.md, "Services"):
// JSON arguments decoded into a typed call of the operator service (stop,
// e-stop, resume, go to, route, inspect, record, alarm ack, control), run in the
// client's own operator session with the same rules as the console (control,
// limits, acks); /console as a console line of that session. Pure: JSON in,
// the call out.
#include <optional>
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
  bool urgent = false;         // stop, e-stop: never refused for the rate, never queued
};
/// Every service, in the order advertised; all answer {"ok": bool, "message": string}.
const std::vector<ServiceDef>& serviceDefs();
/// The JSON Schema of every response.
const std::string& responseSchema();
/// The advertised form of a definition (id left 0).
Service toService(const ServiceDef& d);

/// A request turned into what the session runs: a typed call of the operator
/// service, or (kConsoleLine) one console line after selecting `robot`; or
/// what was wrong with the request.
struct ServiceRequest {
  enum class Call {
    kConsoleLine,
    kStop,
    kEstop,
    kResume,
    kGoto,
    kRoute,
    kInspect,
    kRecordStart,
    kRecordStop,
    kAlarmAck,
    kControlTake,
    kControlRelease
  };
  Call call = Call::kConsoleLine;
  std::string robot;  // "" = the session's selected robot
  double x_m = 0.0, y_m = 0.0;         // kGoto
  std::optional<double> speed_m_s;     // kGoto, kInspect
  std::string route;                   // kRoute, kInspect: a name in config/routes or a file
  std::string name;                    // kRecordStart: the run's name ("" = none)
  std::optional<int> alarm;            // kAlarmAck: the alarm's number (nullopt = all unacknowledged)
  bool force = false;                  // kControlTake
  std::string line;   // kConsoleLine: e.g. "status"
  std::string error;
  bool ok() const { return error.empty(); }
  /// Stop and e-stop: sent at once, never queued behind another call.
  bool urgent() const { return call == Call::kStop || call == Call::kEstop; }
};
ServiceRequest parseServiceRequest(const std::string& service, std::string_view json);

/// The response payload.
std::string serviceResponse(bool ok, const std::string& message);

}  // namespace inspect::server::foxglove
