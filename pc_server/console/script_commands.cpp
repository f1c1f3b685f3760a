// The console's commands of scripts: wait, expect, echo, quit.
#include "pc_server/console/script_commands.hpp"

#include "pc_server/console/console.hpp"
#include "pc_server/console/expect_check.hpp"

namespace inspect::server {

using namespace args;

bool ScriptCommands::cmdWait(const CommandArgs& a) {
  if (!c_.sleepPumping(*a.number("seconds"))) return c_.fail("wait", "interrupted (server stopping)");
  return true;
}

bool ScriptCommands::cmdExpect(const CommandArgs& a) {
  const int line_no = a.line_no;
  const auto parsed = parseExpect(a.words);
  if (const auto* err = std::get_if<std::string>(&parsed)) {
    c_.out() << "EXPECT FAILED (line " << line_no << "): " << *err << "\n";
    c_.countExpect(false);
    return false;
  }
  const auto& spec = std::get<ExpectSpec>(parsed);
  const int64_t deadline = c_.deadlineAfter(spec.within_s);
  FieldReading r;
  bool interrupted = false;
  for (;;) {
    r = readField(spec.field, c_.registry(), c_.selected(), c_.clock().nowNs());
    if (satisfied(spec, r)) {
      c_.out() << "expect ok (line " << line_no << "): " << spec.field << " = " << r.text << "\n";
      c_.countExpect(true);
      return true;
    }
    if (c_.clock().nowNs() >= deadline) break;
    c_.pump();
    if (!c_.clock().sleep(c_.options().poll_period_s)) {
      interrupted = true;
      break;
    }
  }
  c_.out() << "EXPECT FAILED (line " << line_no << "): " << spec.field;
  if (r.ok) c_.out() << " = " << r.text;
  else c_.out() << ": " << r.error;
  c_.out() << ", wanted " << describeWanted(spec) << (interrupted ? " (interrupted)" : "") << "\n";
  c_.countExpect(false);
  return false;
}

bool ScriptCommands::cmdEcho(const CommandArgs& a) {
  c_.out() << a.rest << "\n";
  return true;
}

bool ScriptCommands::cmdQuit(const CommandArgs&) {
  c_.requestQuit();
  return true;
}

// Commands of scripts: waits, checks, output, leaving.
std::vector<ConsoleCommand> ScriptCommands::commands() {
  return {
    {"wait", {{within(number("seconds"), 0, 3600, "s")}}, "pause the console (events still print)",
     "  example: wait 2.5\n", handler(this, &ScriptCommands::cmdWait)},
    {"expect", {{words("<field> <op> <value> [<tol>] [within <seconds>]")}}, "check a value (scripts, tests)",
     "  ops: == != < <= > >= ~   ('~' needs a tolerance: |field - value| <= tol; '+-' before it is optional)\n"
     "  within: poll every 20 ms until true or the time runs out (default: check once).\n"
     "  fields of the selected robot: x y theta v w cmd_v cmd_w wheel_l wheel_r mode faults mcu_faults\n"
     "    connected telemetry_hz telemetry_age sensor_hz battery serial_bad_crc serial_frames_ok\n"
     "    tracking: pos_err ang_err max_pos_err max_ang_err progress ref_x ref_y kp ki kd\n"
     "    people: pattern (0 none, 1 crossing, 2 encountering, 3 leading, 4 confronting) person_m\n"
     "      speed_factor people\n"
     "    navigation: nav_mode goal_dist goal_index goal_count nav_switches dwell\n"
     "    gas: gas0 gas1 gas2 gas3 (channel values) alarms alarms_high (active on the robot)\n"
     "    tuning: gains_version wheel_test_progress\n"
     "  and: robots (number of connected robots).\n"
     "  mode takes IDLE, TELEOP, TRACKING, ESTOP, FAILSAFE, NAVIGATING, WHEEL_TEST; nav_mode takes NONE,\n"
     "  GO_TO_GOAL, AVOID, FOLLOW_CW, FOLLOW_CCW, AT_GOAL; integer fields take 0x.. too.\n"
     "  a field the robot left out reads 'unknown' and fails every comparison; '== unknown' checks that.\n"
     "  examples: expect robots >= 1 within 5\n"
     "            expect x ~ 2.0 0.05 within 10\n"
     "            expect mode == ESTOP within 1\n"
     "            expect nav_mode == FOLLOW_CW within 20\n",
     handler(this, &ScriptCommands::cmdExpect)},
    {"echo", {{opt(rest("text"))}}, "print text (to label script output)", "  example: echo --- leg 2 ---\n",
     handler(this, &ScriptCommands::cmdEcho)},
    {"quit", noArguments(), "leave the console and shut the server down ('exit' too)", "", handler(this, &ScriptCommands::cmdQuit)},
    {"exit", noArguments(), "same as quit", "", handler(this, &ScriptCommands::cmdQuit)},
  };
}

}  // namespace inspect::server
