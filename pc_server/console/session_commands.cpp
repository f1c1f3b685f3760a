// The console's session commands: help, robots, select, status, control.
#include "pc_server/console/session_commands.hpp"

#include <chrono>

#include "pc_server/console/console.hpp"
#include "pc_server/console/text_util.hpp"
#include "pc_server/recording/fleet_presence.hpp"
#include "pc_server/recording/recorder.hpp"

namespace inspect::server {

using namespace args;
using Source = ArgSpec::Source;

bool SessionCommands::cmdHelp(const CommandArgs& a) {
  if (!a.has("command")) {
    c_.out() << c_.helpText();
    return true;
  }
  const std::string text = c_.helpText(a.text("command"));
  if (text.empty()) return c_.fail("help", "unknown command '" + a.text("command") + "'");
  c_.out() << text;
  return true;
}

bool SessionCommands::cmdRobots(const CommandArgs& a) {
  if (a.has("--fleet")) {
    if (!c_.recorder()) return c_.fail("robots", "--fleet reads the catalog, and this server records nothing (--no-record)");
    auto& cat = c_.recorder()->catalog();
    if (cat.serverId().empty())
      return c_.fail("robots", "--fleet needs a catalog that several servers share (--catalog postgresql://...); "
                            "this server's robots are 'robots'");
    c_.out() << fleetTable(cat.listPresence(), cat.listServers(), std::chrono::system_clock::now());
    return true;
  }
  const auto all = c_.registry().snapshots(c_.clock().nowNs());
  if (all.empty()) {
    c_.out() << "no robot has connected yet\n";
    return true;
  }
  c_.out() << "  " << padRight("id", 16) << " " << padRight("connected", 9) << " " << padRight("address", 21) << " "
       << padLeft("tlm Hz", 6) << " " << padRight("mode", 9) << " " << padLeft("tlm age", 8) << "\n";
  for (const auto& r : all) {
    const std::string age = r.has_telemetry ? fmtFixed(r.telemetry_age_s, 2) + " s" : "-";
    const std::string mode = r.has_telemetry ? modeName(r.telemetry.mode()) : "-";
    c_.out() << (r.id == c_.selected() ? "* " : "  ") << padRight(r.id, 16) << " " << padRight(r.connected ? "yes" : "no", 9)
         << " " << padRight(r.address, 21) << " " << padLeft(fmtFixed(r.telemetry_hz, 1), 6) << " "
         << padRight(mode, 9) << " " << padLeft(age, 8) << "\n";
  }
  return true;
}

bool SessionCommands::cmdSelect(const CommandArgs& a) { return c_.select(a.text("robot")); }

bool SessionCommands::cmdStatus(const CommandArgs& a) {
  const std::string robot = a.has("robot") ? a.text("robot") : c_.selected();
  if (robot.empty()) return c_.fail("status", "no robot selected");
  c_.out() << c_.statusText(robot) << "\n";
  return true;
}

bool SessionCommands::cmdControl(const CommandArgs& a) {
  if (!c_.arbiter()) return c_.fail("control", "this console has no sessions (no control arbiter)");
  if (a.form == 0) {
    c_.out() << "this session: " << c_.arbiter()->sessionName(c_.session()) << "\n";
    const auto holders = c_.arbiter()->holders();
    for (const auto& snap : c_.registry().snapshots(c_.clock().nowNs())) {
      const auto it = holders.find(snap.id);
      c_.out() << "  " << snap.id << (snap.connected ? "" : " (not connected)") << ": "
           << (it == holders.end() ? std::string("free")
                                   : it->second.name + (it->second.session == c_.session() ? " <- this session" : ""))
           << "\n";
    }
    return true;
  }
  const auto r = a.has("release") ? c_.service().releaseControl(c_.session(), c_.selected())
                                  : c_.service().takeControl(c_.session(), c_.selected(), a.has("force"), c_.clock().nowNs());
  if (!r.ok()) return c_.fail("control", r.reason);
  c_.out() << r.robot << ": " << r.reason << "\n";
  return true;
}

// Commands of the session: help, robots, selection, status, control.
std::vector<ConsoleCommand> SessionCommands::commands() {
  return {
    {"help", {{opt(completing(word("command", "command name"), Source::kCommands))}}, "list the commands, or explain one",
     "  help          lists every command\n"
     "  help drive    explains one command\n",
     handler(this, &SessionCommands::cmdHelp)},
    {"robots", {{keyword("--fleet")}, {}}, "table of robots: id, connected, address, telemetry Hz, mode, telemetry age",
     "  Lists every robot that connected since the server started; '*' marks the selected one.\n"
     "  --fleet: with a catalog several servers share, every server's robots: online or not\n"
     "  (unknown when its server has not been seen for 10 s), mode, where, and which server\n"
     "  holds the link and where to attach to it (commands go to that server).\n"
     "  example: robots --fleet\n",
     handler(this, &SessionCommands::cmdRobots)},
    {"select", {{completing(word("robot", "robot id"), Source::kRobots)}}, "choose the robot that drive/stop/estop/resume/status/expect act on",
     "  The robot need not be connected yet. With no selection, the first robot to connect\n"
     "  is selected automatically.\n"
     "  example: select robot2\n",
     handler(this, &SessionCommands::cmdSelect)},
    {"status", {{opt(completing(word("robot", "robot id"), Source::kRobots))}}, "one status line of the selected (or named) robot",
     "  example: status\n"
     "  robot1 | TELEOP | v +0.30 w +0.00 | x 1.20 y 0.00 th +0.00 | us 1.23 2.01 -- 0.88 | faults none |"
     " tlm 50 Hz | serial ok\n",
     handler(this, &SessionCommands::cmdStatus)},
    {"control", {CommandForm{}, {subcommand("take"), opt(keyword("force"))}, {keyword("release")}}, "who controls each robot; take or release the selected robot",
     "  One session (console) at a time controls a robot: only its motion commands (drive, teleop,\n"
     "  track, goto, route, inspect, resume, ptz, gains push) reach the robot; the first such command\n"
     "  takes a free robot. Other sessions observe: status, events and runs; stop and estop always work.\n"
     "  control               this session's name and every robot's controlling session\n"
     "  control take          take the selected robot (refused while another session holds it)\n"
     "  control take force    take it over from another session: the robot is stopped first and\n"
     "                        the other session is told\n"
     "  control release       let go of the selected robot (its teleop set-point is cleared)\n",
     handler(this, &SessionCommands::cmdControl)},
  };
}

}  // namespace inspect::server
