#pragma once
// The console's `expect <field> <op> <value> [<tol>] [within <seconds>]`:
// parsing, reading a field of the selected robot, and comparing.
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "pc_server/link/robot_registry.hpp"

namespace inspect::server {

enum class ExpectOp { kEq, kNe, kLt, kLe, kGt, kGe, kNear };

/// A parsed expect line.
struct ExpectSpec {
  std::string field;
  ExpectOp op = ExpectOp::kEq;
  std::string op_text;
  double value = 0;
  std::string value_text;      // as written, for messages
  double tol = 0;              // only for ~
  std::string tol_text;
  double within_s = 0;         // 0 = check once
  bool has_within = false;
  bool unknown = false;        // "== unknown" / "!= unknown": whether the robot left the field out
};

/// A field's value at one instant, or why it has none.
struct FieldReading {
  bool ok = false;
  bool known = true;  // false: the robot left this field out (link protocol 2, "Presence"); text "unknown"
  double value = 0;
  std::string text;   // formatted value ("1.998", "TELEOP", "unknown")
  std::string error;  // when !ok ("no robot selected", "no telemetry from robot1 yet")
};

/// Names of every field expect knows, in help order.
const std::vector<std::string>& expectFields();

/// Parses the words after "expect"; the error string says what is wrong.
std::variant<ExpectSpec, std::string> parseExpect(const std::vector<std::string>& args);

/// Reads `field` of robot `selected` ("" = none) from the registry at `now_ns`.
FieldReading readField(const std::string& field, const RobotRegistry& registry, const std::string& selected,
                       int64_t now_ns);

/// The comparison itself: `actual op value` (with |actual - value| <= tol for ~).
bool compare(ExpectOp op, double actual, double value, double tol);

/// Whether reading `r` meets `spec`: an unknown value meets only "== unknown".
bool satisfied(const ExpectSpec& spec, const FieldReading& r);

/// "~ 2.0 +- 0.05", "< 0.5", "== TELEOP": what the line wanted, for messages.
std::string describeWanted(const ExpectSpec& spec);

/// Mode name ("TELEOP") of a Telemetry.mode value, or the number.
std::string modeName(int mode);

}  // namespace inspect::server
