// The console's gas commands: inspect <route>, alarms, ack (docs/gas.md).
#include <cmath>

#include "pc_server/console/console.hpp"

#include "pc_server/recording/recorder.hpp"
#include "pc_server/scene/site_maps.hpp"
#include "pc_server/operator/route_file.hpp"
#include "pc_server/console/text_util.hpp"
#include "shared/config/config_node.hpp"
#include "shared/util/clock.hpp"

namespace inspect::server {

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

bool Console::cmdInspect(const CommandArgs& a) {
  Route r;
  try {
    r = openRoute(a.text("route"));
  } catch (const config::ConfigError& e) {
    return fail("inspect", e.what());
  }
  const std::optional<double> speed = a.number("speed_m_s");
  if (speed && !commandSpeedOk(*speed))
    return fail("inspect", "speed_m_s '" + a.text("speed_m_s") + "' must be a number in (0, " +
                               fmtShort(kMaxCommandSpeed_m_s) + "] m/s");
  const auto robot = connectedRobot("inspect");
  if (!robot) return false;
  if (!recorder_) out_ << "inspect: note: the server records nothing (--no-record): no run, no report\n";
  std::string summary;
  const Issued issued = service_->inspect(session_, *robot, r, speed, clock_->nowNs(), &summary);
  if (!summary.empty()) out_ << summary << "\n";
  return report(issued, true);
}

bool Console::cmdAlarms(const CommandArgs& a) {
  const bool all = a.has("all");
  const auto list = registry_.alarms(all);
  if (list.empty()) {
    out_ << (all ? "no gas alarms so far\n" : "no active or unacknowledged gas alarms\n");
    return true;
  }
  const int64_t now = clock_->nowNs();
  for (const auto& r : list) out_ << alarmLine(r, now) << "\n";
  return true;
}

bool Console::cmdAck(const CommandArgs& a) {
  std::optional<int> number;
  if (!a.has("all")) {
    std::string n = a.text("number");
    if (!n.empty() && n[0] == '#') n.erase(0, 1);
    const auto pv = parseNumber(n);
    const double v = pv ? *pv : 0.0;
    if (!pv || v < 1 || v != std::floor(v) || v > 1e9)
      return fail("ack", "'" + a.text("number") + "' is not an alarm number (alarms lists them)");
    number = static_cast<int>(v);
  }
  const auto acks = service_->acknowledgeAlarms(session_, number, clock_->nowNs());
  if (!acks.error.empty()) {
    if (!number) {  // nothing left to acknowledge is not an error
      out_ << "ack: " << acks.error << "\n";
      return true;
    }
    return fail("ack", acks.error);
  }
  for (const auto& [r, text] : acks.acked) out_ << r.robot_id << ": " << text << "\n";
  return true;
}

}  // namespace inspect::server
