#include "pc_server/status_line.hpp"

#include <cctype>
#include <cstdio>

#include "pc_server/expect_check.hpp"
#include "pc_server/text_util.hpp"

namespace inspect::server {

std::string faultNames(uint32_t faults) {
  if (faults == 0) return "none";
  std::string s;
  for (uint32_t bit = 1; bit != 0; bit <<= 1) {
    if (!(faults & bit)) continue;
    std::string name = v1::Fault_IsValid(static_cast<int>(bit)) ? v1::Fault_Name(static_cast<v1::Fault>(bit))
                                                                : "bit" + std::to_string(bit);
    if (name.rfind("FAULT_", 0) == 0) name.erase(0, 6);
    s += (s.empty() ? "" : ",") + name;
  }
  return s;
}

std::string statusLine(const std::string& robot_id, const std::optional<RobotSnapshot>& snap) {
  if (!snap) return robot_id + " | not connected yet";
  std::string s = robot_id;
  if (!snap->connected)
    s += " | DISCONNECTED " + fmtFixed(snap->state_age_s, 1) + " s ago (" + snap->close_reason + ")";
  if (!snap->has_telemetry) return s + (snap->connected ? " | connected, no telemetry yet" : "");
  const auto& t = snap->telemetry;
  s += " | " + modeName(t.mode());
  s += " | v " + fmtSigned(t.v_m_s()) + " w " + fmtSigned(t.w_rad_s());
  s += " | x " + fmtFixed(t.pose().x_m()) + " y " + fmtFixed(t.pose().y_m()) + " th " + fmtSigned(t.pose().theta_rad());
  if (t.mode() == v1::TRACKING)
    s += " | " + t.track_controller() + " " + fmtFixed(100.0 * t.track_progress(), 0) + "% err " +
         fmtFixed(t.position_error_m(), 3) + " m " + fmtFixed(t.angle_error_rad(), 3) + " rad kp " + fmtFixed(t.kp(), 1);
  if (t.mode() == v1::NAVIGATING) {
    char nav[96];
    std::snprintf(nav, sizeof nav, " goal %u/%u %s m sw %u", t.goal_index() + 1, t.goal_count(),
                  fmtFixed(t.goal_distance_m()).c_str(), t.nav_switches());
    s += " | nav " + t.nav_mode() + nav;
  }
  if (t.nearest_person_m() >= 0) {
    std::string pat = v1::HumanPattern_Name(t.pattern());
    for (auto& ch : pat) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    s += " | person " + fmtFixed(t.nearest_person_m(), 1) + " m " + (t.pattern() == v1::PATTERN_NONE ? "?" : pat) +
         " speed x" + fmtFixed(t.speed_factor(), 2);
  }
  if (t.ultrasonic_m_size() > 0) {
    s += " | us";
    for (double r : t.ultrasonic_m()) s += r < 0 ? " --" : " " + fmtFixed(r);
  }
  if (t.gas_size() > 0) {
    s += " | gas";
    for (double g : t.gas()) s += " " + fmtShort(g, 1);
  }
  if (t.battery_v() > 0) s += " | bat " + fmtFixed(t.battery_v(), 1) + " V";
  s += " | faults " + faultNames(t.faults());
  s += " | tlm " + fmtFixed(snap->telemetry_hz, 0) + " Hz";
  if (snap->connected && snap->telemetry_age_s > 0.5) s += " (stale " + fmtFixed(snap->telemetry_age_s, 1) + " s)";
  s += (t.faults() & v1::FAULT_SERIAL_DOWN) ? " | serial DOWN" : " | serial ok";
  return s;
}

bool statusIsAlarm(const std::optional<RobotSnapshot>& snap) {
  if (!snap || !snap->connected) return true;
  if (!snap->has_telemetry) return false;
  const auto m = snap->telemetry.mode();
  return m == v1::ESTOP || m == v1::FAILSAFE || snap->telemetry.faults() != 0;
}

}  // namespace inspect::server
