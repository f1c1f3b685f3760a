// The console's gas commands: inspect <route>, alarms, ack (docs/gas.md).
#include <cmath>

#include "pc_server/console/console.hpp"
#include "pc_server/console/gas_commands.hpp"
#include "pc_server/console/text_util.hpp"
#include "pc_server/operator/route_file.hpp"
#include "pc_server/recording/recorder.hpp"
#include "pc_server/scene/site_maps.hpp"
#include "shared/config/config_node.hpp"
#include "shared/util/clock.hpp"

namespace inspect::server {

using namespace args;

namespace {

std::string value(double v, const std::string& unit) {
  return (std::isnan(v) ? std::string("--") : fmtShort(v, 2)) + (unit.empty() ? "" : " " + unit);
}

// "#3 robot1 H2S HIGH 12.3 ppm (A2 10 ppm, worst 15.1 ppm) at (2.10, 2.95): raised 14.2 s ago, active, unacknowledged"
std::string alarmLine(const AlarmRecord& r, int64_t now_ns) {
  const auto& a = r.alarm;
  std::string s = "#" + std::to_string(r.number) + " " + r.robot_id + " " + a.channel_name() + " " +
                  v1::GasAlarm::Level_Name(a.level());
  if (a.level() == v1::GasAlarm::SENSOR_FAULT) {
    s += " " + a.fault() + " (reading " + value(a.value(), a.unit()) + ")";
  } else {
    s += " " + value(a.value(), a.unit()) + " (" + (a.level() == v1::GasAlarm::HIGH ? "A2 " : "A1 ") +
         value(a.threshold(), a.unit()) + ", worst " + value(a.peak(), a.unit()) + ")";
  }
  s += " at (" + fmtFixed(a.pose().x_m()) + ", " + fmtFixed(a.pose().y_m()) + "): raised " +
       fmtFixed(static_cast<double>(now_ns - r.raised_ns) * 1e-9, 1) + " s ago, ";
  s += r.active() ? std::string("ACTIVE")
                  : "cleared after " + fmtFixed(static_cast<double>(r.cleared_ns - r.raised_ns) * 1e-9, 1) + " s";
  s += r.acked ? ", acknowledged" : ", unacknowledged";
  return s;
}

}  // namespace

bool GasCommands::cmdInspect(const CommandArgs& a) {
  Route r;
  try {
    r = openRoute(a.text("route"));
  } catch (const config::ConfigError& e) {
    return c_.fail("inspect", e.what());
  }
  const std::optional<double> speed = a.number("speed_m_s");
  if (speed && !commandSpeedOk(*speed))
    return c_.fail("inspect", "speed_m_s '" + a.text("speed_m_s") + "' must be a number in (0, " +
                               fmtShort(kMaxCommandSpeed_m_s) + "] m/s");
  const auto robot = c_.connectedRobot("inspect");
  if (!robot) return false;
  if (!c_.recorder()) c_.out() << "inspect: note: the server records nothing (--no-record): no run, no report\n";
  std::string summary;
  const Issued issued = c_.service().inspect(c_.session(), *robot, r, speed, c_.clock().nowNs(), &summary);
  if (!summary.empty()) c_.out() << summary << "\n";
  return c_.report(issued, true);
}

bool GasCommands::cmdAlarms(const CommandArgs& a) {
  const bool all = a.has("all");
  const auto list = c_.registry().alarms(all);
  if (list.empty()) {
    c_.out() << (all ? "no gas alarms so far\n" : "no active or unacknowledged gas alarms\n");
    return true;
  }
  const int64_t now = c_.clock().nowNs();
  for (const auto& r : list) c_.out() << alarmLine(r, now) << "\n";
  return true;
}

bool GasCommands::cmdAck(const CommandArgs& a) {
  std::optional<int> number;
  if (!a.has("all")) {
    std::string n = a.text("number");
    if (!n.empty() && n[0] == '#') n.erase(0, 1);
    const auto pv = parseNumber(n);
    const double v = pv ? *pv : 0.0;
    if (!pv || v < 1 || v != std::floor(v) || v > 1e9)
      return c_.fail("ack", "'" + a.text("number") + "' is not an alarm number (alarms lists them)");
    number = static_cast<int>(v);
  }
  const auto acks = c_.service().acknowledgeAlarms(c_.session(), number, c_.clock().nowNs());
  if (!acks.error.empty()) {
    if (!number) {  // nothing left to acknowledge is not an error
      c_.out() << "ack: " << acks.error << "\n";
      return true;
    }
    return c_.fail("ack", acks.error);
  }
  for (const auto& [r, text] : acks.acked) c_.out() << r.robot_id << ": " << text << "\n";
  return true;
}

// Commands of gas inspection and alarms (docs/gas.md).
std::vector<ConsoleCommand> GasCommands::commands() {
  return {
    {"inspect", {{word("route"), opt(number("speed_m_s"))}}, "run a gas inspection route as a recorded run",
     "  <route> is a file or a name in config/routes/ (config/routes/<name>.yaml). The route's\n"
     "  points may carry dwell_s (the robot stops there), a camera preset (ptz: {pan_deg,\n"
     "  tilt_deg} or {home: true}) and a label; `map` names the site's world file, which the\n"
     "  run's report draws the concentration maps on. The robot navigates with the behaviour\n"
     "  strategy (people get right of way, Eq 9) and reacts to a gas HIGH alarm as configured\n"
     "  (client.yaml safety.gas_reaction: continue, stop = hold until resume, retreat). The run\n"
     "  is recorded (named 'inspection <name>') and ends with the route. Then: report <run-id>.\n"
     "  example: inspect gas_lab_inspection\n",
     handler(this, &GasCommands::cmdInspect)},
    {"alarms", {{opt(keyword("all"))}}, "gas alarms and gas sensor faults: active and unacknowledged ones, or all",
     "  One line per alarm: #number, robot, gas, level (LOW = A1, HIGH = A2, SENSOR_FAULT with\n"
     "  stuck, out_of_range or no_data), the reading and threshold, the worst reading, where the\n"
     "  robot was, how long ago it was raised, whether it is still active and acknowledged.\n"
     "  The robot raises and clears alarms (thresholds with hysteresis, minimum duration); the\n"
     "  operator acknowledges them with ack. Raised alarms print at once, in red with a bell on a\n"
     "  terminal, and the status line shows '| ALARM ...' while they are active.\n",
     handler(this, &GasCommands::cmdAlarms)},
    {"ack", {{keyword("all")}, {word("number")}}, "acknowledge a gas alarm (alarms lists the numbers)",
     "  Acknowledging does not clear an alarm (the robot does, when the gas is gone); it records\n"
     "  that the operator has seen it (catalog and run).\n"
     "  example: ack 3\n",
     handler(this, &GasCommands::cmdAck)},
  };
}

}  // namespace inspect::server
