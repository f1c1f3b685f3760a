#include "pc_server/console/expect_check.hpp"

#include <limits>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <functional>
#include <map>

#include "pc_server/console/text_util.hpp"

namespace inspect::server {

namespace {

using Value = std::optional<double>;  // nullopt = unknown: the robot left the field out

struct FieldDef {
  std::string name;
  bool integer;        // printed without decimals
  bool needs_robot;    // reads the selected robot
  bool needs_telemetry;
  std::function<Value(const RobotSnapshot&)> get;
};

// An `optional` Telemetry field (link protocol 2): its value, or unknown.
template <auto Has, auto Get>
Value opt(const RobotSnapshot& s) {
  return (s.telemetry.*Has)() ? Value(static_cast<double>((s.telemetry.*Get)())) : std::nullopt;
}

// Telemetry.nav_mode is a string; expect compares its index here ("" = NONE).
constexpr std::array<const char*, 9> kNavModes = {"NONE",       "GO_TO_GOAL", "AVOID", "FOLLOW_CW", "FOLLOW_CCW",
                                                  "AT_GOAL",    "DWELL",      "GAS_HOLD", "RETREAT"};

// A channel past the end of Telemetry.gas is unknown; NaN = the sensor gives no data.
Value gasValue(const RobotSnapshot& s, int i) {
  return i < s.telemetry.gas_size() ? Value(s.telemetry.gas(i)) : std::nullopt;
}

double alarmCount(const RobotSnapshot& s, bool high_only) {
  int n = 0;
  for (const auto& a : s.telemetry.active_alarms()) n += !high_only || a.level() == v1::GasAlarm::HIGH;
  return n;
}

double navModeNumber(const std::string& name) {
  if (name.empty()) return 0.0;
  for (std::size_t i = 1; i < kNavModes.size(); ++i)
    if (name == kNavModes[i]) return static_cast<double>(i);
  return -1.0;  // a mode this console does not know
}

std::optional<int> navModeFromName(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::toupper(c); });
  for (std::size_t i = 0; i < kNavModes.size(); ++i)
    if (text == kNavModes[i]) return static_cast<int>(i);
  return std::nullopt;
}

const std::vector<FieldDef>& fieldDefs() {
  using S = RobotSnapshot;
  using T = v1::Telemetry;
  static const std::vector<FieldDef> kDefs = {
      {"x", false, true, true, [](const S& s) { return s.telemetry.pose().x_m(); }},
      {"y", false, true, true, [](const S& s) { return s.telemetry.pose().y_m(); }},
      {"theta", false, true, true, [](const S& s) { return s.telemetry.pose().theta_rad(); }},
      {"v", false, true, true, opt<&T::has_v_m_s, &T::v_m_s>},
      {"w", false, true, true, opt<&T::has_w_rad_s, &T::w_rad_s>},
      {"cmd_v", false, true, true, opt<&T::has_cmd_v_m_s, &T::cmd_v_m_s>},
      {"cmd_w", false, true, true, opt<&T::has_cmd_w_rad_s, &T::cmd_w_rad_s>},
      {"wheel_l", false, true, true, opt<&T::has_wheel_left_rad_s, &T::wheel_left_rad_s>},
      {"wheel_r", false, true, true, opt<&T::has_wheel_right_rad_s, &T::wheel_right_rad_s>},
      {"mode", true, true, true, [](const S& s) { return static_cast<double>(s.telemetry.mode()); }},
      {"faults", true, true, true, [](const S& s) { return static_cast<double>(s.telemetry.faults()); }},
      {"mcu_faults", true, true, true, [](const S& s) { return static_cast<double>(s.telemetry.mcu_faults()); }},
      {"connected", true, true, false, [](const S& s) { return s.connected ? 1.0 : 0.0; }},
      {"telemetry_hz", false, true, false, [](const S& s) { return s.telemetry_hz; }},
      {"telemetry_age", false, true, true, [](const S& s) { return s.telemetry_age_s; }},
      {"sensor_hz", false, true, true, opt<&T::has_sensor_rate_hz, &T::sensor_rate_hz>},
      {"battery", false, true, true, opt<&T::has_battery_v, &T::battery_v>},
      {"serial_bad_crc", true, true, true,
       [](const S& s) { return static_cast<double>(s.telemetry.serial().bad_crc()); }},
      {"serial_frames_ok", true, true, true,
       [](const S& s) { return static_cast<double>(s.telemetry.serial().frames_ok()); }},
      {"pos_err", false, true, true, opt<&T::has_position_error_m, &T::position_error_m>},
      {"ang_err", false, true, true, opt<&T::has_angle_error_rad, &T::angle_error_rad>},
      {"max_pos_err", false, true, true, opt<&T::has_track_max_position_error_m, &T::track_max_position_error_m>},
      {"max_ang_err", false, true, true, opt<&T::has_track_max_angle_error_rad, &T::track_max_angle_error_rad>},
      {"progress", false, true, true, opt<&T::has_track_progress, &T::track_progress>},
      {"ref_x", false, true, true,
       [](const S& s) { return s.telemetry.has_reference() ? Value(s.telemetry.reference().x_m()) : std::nullopt; }},
      {"ref_y", false, true, true,
       [](const S& s) { return s.telemetry.has_reference() ? Value(s.telemetry.reference().y_m()) : std::nullopt; }},
      {"kp", false, true, true, opt<&T::has_kp, &T::kp>},
      {"ki", false, true, true, opt<&T::has_ki, &T::ki>},
      {"kd", false, true, true, opt<&T::has_kd, &T::kd>},
      {"pattern", true, true, true, [](const S& s) { return static_cast<double>(s.telemetry.pattern()); }},
      {"person_m", false, true, true, opt<&T::has_nearest_person_m, &T::nearest_person_m>},
      {"speed_factor", false, true, true, opt<&T::has_speed_factor, &T::speed_factor>},
      {"people", true, true, true, opt<&T::has_people_tracked, &T::people_tracked>},
      {"nav_mode", true, true, true, [](const S& s) { return navModeNumber(s.telemetry.nav_mode()); }},
      {"goal_dist", false, true, true, opt<&T::has_goal_distance_m, &T::goal_distance_m>},
      {"goal_index", true, true, true, [](const S& s) { return static_cast<double>(s.telemetry.goal_index()); }},
      {"goal_count", true, true, true, [](const S& s) { return static_cast<double>(s.telemetry.goal_count()); }},
      {"nav_switches", true, true, true, [](const S& s) { return static_cast<double>(s.telemetry.nav_switches()); }},
      {"dwell", false, true, true, opt<&T::has_dwell_remaining_s, &T::dwell_remaining_s>},
      {"gains_version", true, true, true, [](const S& s) { return static_cast<double>(s.telemetry.gains_version()); }},
      {"wheel_test_progress", false, true, true, opt<&T::has_wheel_test_progress, &T::wheel_test_progress>},
      {"alarms", true, true, true, [](const S& s) { return alarmCount(s, false); }},
      {"alarms_high", true, true, true, [](const S& s) { return alarmCount(s, true); }},
      {"gas0", false, true, true, [](const S& s) { return gasValue(s, 0); }},
      {"gas1", false, true, true, [](const S& s) { return gasValue(s, 1); }},
      {"gas2", false, true, true, [](const S& s) { return gasValue(s, 2); }},
      {"gas3", false, true, true, [](const S& s) { return gasValue(s, 3); }},
      {"robots", true, false, false, nullptr},
  };
  return kDefs;
}

const FieldDef* findField(const std::string& name) {
  for (const auto& f : fieldDefs())
    if (f.name == name) return &f;
  return nullptr;
}

const std::map<std::string, ExpectOp>& ops() {
  static const std::map<std::string, ExpectOp> kOps = {{"==", ExpectOp::kEq}, {"!=", ExpectOp::kNe},
                                                       {"<", ExpectOp::kLt},  {"<=", ExpectOp::kLe},
                                                       {">", ExpectOp::kGt},  {">=", ExpectOp::kGe},
                                                       {"~", ExpectOp::kNear}};
  return kOps;
}

std::optional<int> modeFromName(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::toupper(c); });
  v1::Mode m{};
  if (!v1::Mode_Parse(text, &m)) return std::nullopt;
  return static_cast<int>(m);
}

std::string fieldList() {
  std::string s;
  for (const auto& f : fieldDefs()) s += (s.empty() ? "" : ", ") + f.name;
  return s;
}

}  // namespace

const std::vector<std::string>& expectFields() {
  static const std::vector<std::string> kNames = [] {
    std::vector<std::string> v;
    for (const auto& f : fieldDefs()) v.push_back(f.name);
    return v;
  }();
  return kNames;
}

std::string modeName(int mode) {
  if (v1::Mode_IsValid(mode) && mode != v1::MODE_UNSPECIFIED) return v1::Mode_Name(static_cast<v1::Mode>(mode));
  return mode == 0 ? "UNSPECIFIED" : std::to_string(mode);
}

std::variant<ExpectSpec, std::string> parseExpect(const std::vector<std::string>& args) {
  static const std::string kSyntax = "syntax: expect <field> <op> <value> [<tol>] [within <seconds>]";
  if (args.size() < 3) return "expect: too few words; " + kSyntax;
  ExpectSpec s;
  s.field = args[0];
  const FieldDef* def = findField(s.field);
  if (!def) return "expect: unknown field '" + s.field + "' (fields: " + fieldList() + ")";
  const auto op = ops().find(args[1]);
  if (op == ops().end()) return "expect: unknown operator '" + args[1] + "' (use == != < <= > >= ~)";
  s.op = op->second;
  s.op_text = args[1];
  s.value_text = args[2];
  if (args[2] == kUnknown) {
    // expect person_m == unknown: the robot left the field out (link protocol 2, "Presence").
    if (s.op != ExpectOp::kEq && s.op != ExpectOp::kNe)
      return "expect: 'unknown' goes with == or != only (expect person_m == unknown)";
    s.unknown = true;
  } else if (const auto v = parseNumber(args[2])) {
    s.value = *v;
  } else if (s.field == "mode" && modeFromName(args[2])) {
    s.value = *modeFromName(args[2]);
  } else if (s.field == "nav_mode" && navModeFromName(args[2])) {
    s.value = *navModeFromName(args[2]);
  } else if (const auto i = parseInteger(args[2]); i && def->integer) {
    s.value = static_cast<double>(*i);  // e.g. faults == 0x4
  } else {
    return "expect: '" + args[2] + "' is not a number" +
           (s.field == "mode" ? " or a mode (IDLE, TELEOP, TRACKING, ESTOP, FAILSAFE, NAVIGATING, WHEEL_TEST)"
            : s.field == "nav_mode" ? " or a navigation mode (NONE, GO_TO_GOAL, AVOID, FOLLOW_CW, FOLLOW_CCW, AT_GOAL, DWELL, GAS_HOLD, RETREAT)"
                                    : "");
  }
  std::size_t i = 3;
  if (s.op == ExpectOp::kNear) {
    if (i < args.size() && args[i] == "+-") ++i;
    if (i >= args.size() || args[i] == "within") return "expect: '~' needs a tolerance: expect x ~ 2.0 0.05";
    const auto tol = parseNumber(args[i]);
    if (!tol || *tol < 0) return "expect: tolerance '" + args[i] + "' is not a number >= 0";
    s.tol = *tol;
    s.tol_text = args[i];
    ++i;
  }
  if (i < args.size()) {
    if (args[i] != "within") {
      if (s.op != ExpectOp::kNear && parseNumber(args[i]))
        return "expect: a tolerance is only allowed with '~'; " + kSyntax;
      return "expect: unexpected '" + args[i] + "'; " + kSyntax;
    }
    if (i + 1 >= args.size()) return "expect: 'within' needs a number of seconds";
    const auto w = parseNumber(args[i + 1]);
    if (!w || *w < 0 || *w > 3600) return "expect: within '" + args[i + 1] + "' is not a number of seconds in [0, 3600]";
    s.within_s = *w;
    s.has_within = true;
    i += 2;
  }
  if (i < args.size()) return "expect: unexpected '" + args[i] + "' at the end; " + kSyntax;
  return s;
}

FieldReading readField(const std::string& field, const RobotRegistry& registry, const std::string& selected,
                       int64_t now_ns) {
  FieldReading r;
  const FieldDef* def = findField(field);
  if (!def) {
    r.error = "unknown field '" + field + "'";
    return r;
  }
  Value v = 0.0;
  if (!def->needs_robot) {
    v = registry.connectedCount();
  } else {
    if (selected.empty()) {
      r.error = "no robot selected";
      return r;
    }
    const auto snap = registry.snapshot(selected, now_ns);
    if (!snap) {
      if (field == "connected") {
        v = 0;  // selected before it ever connected
      } else if (field == "telemetry_hz") {
        v = 0;
      } else {
        r.error = selected + " has never connected";
        return r;
      }
    } else {
      if (def->needs_telemetry && !snap->has_telemetry) {
        r.error = "no telemetry from " + selected + " yet";
        return r;
      }
      v = def->get(*snap);
    }
  }
  r.ok = true;
  r.known = v.has_value();
  if (!r.known) {
    r.text = kUnknown;
    return r;
  }
  r.value = *v;
  if (field == "mode") r.text = modeName(static_cast<int>(r.value));
  else if (field == "nav_mode")
    r.text = r.value >= 0 && r.value < static_cast<double>(kNavModes.size()) ? kNavModes[static_cast<std::size_t>(r.value)] : "?";
  else if (def->integer) r.text = std::to_string(static_cast<long long>(r.value));
  else r.text = fmtShort(r.value, 3);
  return r;
}

bool satisfied(const ExpectSpec& spec, const FieldReading& r) {
  if (!r.ok) return false;
  if (spec.unknown) return (spec.op == ExpectOp::kEq) == !r.known;
  return r.known && compare(spec.op, r.value, spec.value, spec.tol);
}

bool compare(ExpectOp op, double actual, double value, double tol) {
  switch (op) {
    case ExpectOp::kEq: return actual == value;
    case ExpectOp::kNe: return actual != value;
    case ExpectOp::kLt: return actual < value;
    case ExpectOp::kLe: return actual <= value;
    case ExpectOp::kGt: return actual > value;
    case ExpectOp::kGe: return actual >= value;
    case ExpectOp::kNear: return std::fabs(actual - value) <= tol;
  }
  return false;
}

std::string describeWanted(const ExpectSpec& spec) {
  std::string s = spec.op_text + " " + spec.value_text;
  if (spec.op == ExpectOp::kNear) s += " +- " + spec.tol_text;
  if (spec.has_within) s += " within " + fmtShort(spec.within_s) + " s";
  return s;
}

}  // namespace inspect::server
