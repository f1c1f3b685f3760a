#include "pc_server/foxglove/bridge_services.hpp"

#include <cmath>

#include <nlohmann/json.hpp>


namespace inspect::server::foxglove {

using Json = nlohmann::json;

namespace {

const char* kRobotProp = R"("robot": {"type": "string", "description": "robot id; default: the session's selected robot"})";

std::string schema(const std::string& props, const std::string& required = "") {
  return std::string(R"({"type": "object", "properties": {)") + kRobotProp + (props.empty() ? "" : ", " + props) +
         "}" + (required.empty() ? "" : R"(, "required": [)" + required + "]") + "}";
}

/// A console word from a client: printable, no spaces (console lines split on them).
bool plainWord(const std::string& s) {
  if (s.empty() || s.size() > 200) return false;
  for (const unsigned char c : s)
    if (c <= ' ' || c == 0x7f || c == '#') return false;
  return true;
}

struct BadRequest {
  std::string what;
};

double number(const Json& j, const char* key, bool required, double fallback = NAN) {
  const auto it = j.find(key);
  if (it == j.end() || it->is_null()) {
    if (required) throw BadRequest{"missing \"" + std::string(key) + "\" (a number)"};
    return fallback;
  }
  if (!it->is_number()) throw BadRequest{"\"" + std::string(key) + "\" must be a number"};
  const double v = it->get<double>();
  if (!std::isfinite(v)) throw BadRequest{"\"" + std::string(key) + "\" must be finite"};
  return v;
}
std::string word(const Json& j, const char* key, bool required) {
  const auto it = j.find(key);
  if (it == j.end() || it->is_null()) {
    if (required) throw BadRequest{"missing \"" + std::string(key) + "\" (a string)"};
    return "";
  }
  if (!it->is_string()) throw BadRequest{"\"" + std::string(key) + "\" must be a string"};
  const std::string s = it->get<std::string>();
  if (!plainWord(s)) throw BadRequest{"\"" + std::string(key) + "\" must be one word (1-200 printable characters, no spaces or #)"};
  return s;
}
/// Words separated by single spaces (a run name): printable, no #.
std::string text(const Json& j, const char* key) {
  const auto it = j.find(key);
  if (it == j.end() || it->is_null()) return "";
  const std::string s = it->is_string() ? it->get<std::string>() : std::string("\x01");
  bool ok = !s.empty() && s.size() <= 200 && s.front() != ' ' && s.back() != ' ';
  for (const unsigned char c : s) ok = ok && c >= ' ' && c != 0x7f && c != '#';
  if (!ok) throw BadRequest{"\"" + std::string(key) + "\" must be text of 1-200 printable characters without #"};
  return s;
}
bool flag(const Json& j, const char* key) {
  const auto it = j.find(key);
  if (it == j.end() || it->is_null()) return false;
  if (!it->is_boolean()) throw BadRequest{"\"" + std::string(key) + "\" must be true or false"};
  return it->get<bool>();
}

}  // namespace

const std::vector<ServiceDef>& serviceDefs() {
  static const std::vector<ServiceDef> defs{
      {"/stop", "inspect/Stop", schema(""), "zero the robot's set-point (always allowed)", true},
      {"/estop", "inspect/EStop", schema(""), "emergency stop, latched until /resume (always allowed)", true},
      {"/resume", "inspect/Resume", schema(""), "clear a latched e-stop or failsafe (needs control)"},
      {"/goto", "inspect/GoTo",
       schema(R"("x": {"type": "number"}, "y": {"type": "number"}, "speed": {"type": "number", "description": "m/s, optional"})",
              R"("x", "y")"),
       "navigate to (x, y) of the robot's odometry frame"},
      {"/route", "inspect/Route", schema(R"("route": {"type": "string", "description": "name in config/routes or a file"})", R"("route")"),
       "run a route file"},
      {"/inspect", "inspect/Inspect",
       schema(R"("route": {"type": "string"}, "speed": {"type": "number", "description": "m/s, optional"})", R"("route")"),
       "a recorded gas inspection round"},
      {"/record_start", "inspect/RecordStart", schema(R"("name": {"type": "string", "description": "run name, optional"})"),
       "start recording a run"},
      {"/record_stop", "inspect/RecordStop", schema(""), "end the run being recorded"},
      {"/alarm_ack", "inspect/AlarmAck",
       schema(R"("number": {"type": "integer", "minimum": 1, "description": "the alarm's number (/alarms); omitted: every unacknowledged alarm"})"),
       "acknowledge gas alarms"},
      {"/control_take", "inspect/ControlTake",
       schema(R"("force": {"type": "boolean", "description": "take over from another session"})"),
       "take control of the robot (motion needs it)"},
      {"/control_release", "inspect/ControlRelease", schema(""), "release control of the robot"},
      {"/console", "inspect/Console",
       schema(R"("command": {"type": "string", "description": "any console command line, as docs/console.md lists"})", R"("command")"),
       "any console command, with the console's rules"},
  };
  return defs;
}

const std::string& responseSchema() {
  static const std::string s =
      R"({"type": "object", "properties": {"ok": {"type": "boolean"}, "message": {"type": "string"}}, "required": ["ok", "message"]})";
  return s;
}

Service toService(const ServiceDef& d) {
  Service s;
  s.name = d.name;
  s.type = d.type;
  s.request_schema = d.request_schema;
  s.response_schema = responseSchema();
  s.urgent = d.urgent;
  return s;
}

ServiceRequest parseServiceRequest(const std::string& service, std::string_view json) {
  ServiceRequest r;
  Json j = json.empty() ? Json::object() : Json::parse(json, nullptr, false);
  if (j.is_discarded()) {
    r.error = service + ": the request is not valid JSON";
    return r;
  }
  if (j.is_null()) j = Json::object();
  if (!j.is_object()) {
    r.error = service + ": the request must be a JSON object";
    return r;
  }
  try {
    r.robot = word(j, "robot", false);
    using Call = ServiceRequest::Call;
    const auto speed = [&]() -> std::optional<double> {
      const double v = number(j, "speed", false);
      return std::isnan(v) ? std::nullopt : std::optional<double>(v);
    };
    if (service == "/stop") {
      r.call = Call::kStop;
    } else if (service == "/estop") {
      r.call = Call::kEstop;
    } else if (service == "/resume") {
      r.call = Call::kResume;
    } else if (service == "/goto") {
      r.call = Call::kGoto;
      r.x_m = number(j, "x", true);
      r.y_m = number(j, "y", true);
      r.speed_m_s = speed();
    } else if (service == "/route") {
      r.call = Call::kRoute;
      r.route = word(j, "route", true);
    } else if (service == "/inspect") {
      r.call = Call::kInspect;
      r.route = word(j, "route", true);
      r.speed_m_s = speed();
    } else if (service == "/record_start") {
      r.call = Call::kRecordStart;
      r.name = text(j, "name");
    } else if (service == "/record_stop") {
      r.call = Call::kRecordStop;
    } else if (service == "/alarm_ack") {
      r.call = Call::kAlarmAck;
      const double n = number(j, "number", false);
      if (!std::isnan(n)) {
        if (n < 1 || n > 1e9 || n != std::floor(n)) throw BadRequest{"\"number\" must be an alarm number (1, 2, ...)"};
        r.alarm = static_cast<int>(n);
      }
    } else if (service == "/control_take") {
      r.call = Call::kControlTake;
      r.force = flag(j, "force");
    } else if (service == "/control_release") {
      r.call = Call::kControlRelease;
    } else if (service == "/console") {
      const auto it = j.find("command");
      if (it == j.end() || !it->is_string()) throw BadRequest{"missing \"command\" (a string)"};
      std::string line = it->get<std::string>();
      if (line.size() > 4096) throw BadRequest{"\"command\" is longer than 4096 characters"};
      for (const unsigned char c : line)
        if (c < ' ' && c != '\t') throw BadRequest{"\"command\" must be one line without control characters"};
      r.line = std::move(line);
    } else {
      throw BadRequest{"unknown service"};
    }
  } catch (const BadRequest& b) {
    r.error = service + ": " + b.what;
  }
  return r;
}

std::string serviceResponse(bool ok, const std::string& message) {
  return Json{{"ok", ok}, {"message", message}}.dump(-1, ' ', false, Json::error_handler_t::replace);
}

}  // namespace inspect::server::foxglove
