// The console's `gains` command: show, set, use, push and revert the
// tracking gains (docs/tuning.md).
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "pc_server/console/console.hpp"
#include "pc_server/console/text_util.hpp"
#include "pc_server/console/tuning_commands.hpp"
#include "pc_server/console/tuning_state.hpp"
#include "pc_server/recording/recorder.hpp"
#include "pc_server/tuning/plant_id.hpp"
#include "pc_server/tuning/tuner.hpp"
#include "pc_server/tuning/tuning_report.hpp"
#include "shared/config/config_node.hpp"
#include "shared/config/control_config.hpp"
#include "shared/config/gains_file.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/fuzzy/fis_reader.hpp"
#include "shared/fuzzy/fis_writer.hpp"
#include "shared/net/gains_proto.hpp"
#include "shared/util/clock.hpp"
#include "sim/robot_plant.hpp"

namespace inspect::server {

bool TuningCommands::gainsShow(const CommandArgs& a, TuningState& ts) {
  const std::string robot = a.has("robot") ? a.text("robot") : c_.selected();
  std::optional<RobotSnapshot> snap;
  if (!robot.empty()) snap = c_.registry().snapshot(robot, c_.clock().nowNs());
  const bool have_robot = snap && snap->gains_known;
  const control::GainSet rg = have_robot ? net::fromProto(snap->gains) : control::GainSet{};
  char head[200];
  std::snprintf(head, sizeof head, "%-6s %12s %12s %12s %12s\n", "gain", "working",
                have_robot ? (robot + " v" + std::to_string(snap->gains_version)).c_str() : "robot", "paper",
                ts.tuned ? "tuned" : "");
  c_.out() << head;
  for (const char* n : control::kGainNames) {
    char row[200];
    const std::string rv = have_robot ? fmtShort(control::gainValue(rg, n), 5) : std::string("--");
    const std::string tv = ts.tuned ? fmtShort(control::gainValue(*ts.tuned, n), 5) : std::string();
    std::snprintf(row, sizeof row, "%-6s %12s %12s %12s %12s\n", n, fmtShort(control::gainValue(ts.working, n), 5).c_str(),
                  rv.c_str(), fmtShort(control::gainValue(ts.paper, n), 5).c_str(), tv.c_str());
    c_.out() << row;
  }
  c_.out() << "fuzzy system: " << ts.fis.name << (ts.fis_imported ? " (imported; pushed with the gains)" : "")
       << (have_robot && !snap->hello.fis_name().empty() ? "; robot's: " + snap->hello.fis_name() : std::string())
       << "\n";
  if (!have_robot && !robot.empty()) c_.out() << "(" << robot << " has not announced its gains)\n";
  return true;
}

bool TuningCommands::gainsSet(const CommandArgs& a, TuningState& ts) {
  if (const std::string& set = a.text("preset"); !set.empty()) {
    if (set == "paper") ts.working = ts.paper;
    if (set == "tuned") {
      if (!ts.tuned) return c_.fail("gains", "nothing tuned yet (tune)");
      ts.working = *ts.tuned;
    }
    if (set == "robot") {
      const auto snap = c_.selected().empty() ? std::optional<RobotSnapshot>() : c_.registry().snapshot(c_.selected(), c_.clock().nowNs());
      if (!snap || !snap->gains_known) return c_.fail("gains", "the selected robot has not announced its gains");
      ts.working = net::fromProto(snap->gains);
    }
    c_.out() << "gains: working set = " << set << ": " << gainsText(ts.working) << "\n";
    return true;
  }
  const auto& args = a.list("gains");
  control::GainSet next = ts.working;
  for (std::size_t i = 0; i < args.size(); ++i) {
    std::string k, v;
    if (!splitKeyValue(args[i], k, v)) {
      // "gains set kp 12" form
      if (args.size() == 2 && i == 0) {
        k = args[0];
        v = args[1];
        i = 1;
      } else {
        return c_.fail("gains", "'" + args[i] + "' is not name=value");
      }
    }
    double* slot = control::gainByName(next, k);
    if (!slot) return c_.fail("gains", "unknown gain '" + k + "' (kp ki kd ke kec k1 k2 k3 a1 a2 a3)");
    const auto x = parseNumber(v);
    if (!x) return c_.fail("gains", k + ": '" + v + "' is not a number");
    *slot = *x;
  }
  if (const std::string why = control::validateGains(next); !why.empty()) return c_.fail("gains", why + " (nothing changed)");
  ts.working = next;
  c_.out() << "gains: working set: " << gainsText(ts.working) << "\n";
  return true;
}

bool TuningCommands::cmdGains(const CommandArgs& a) {
  TuningState* ts = tuning("gains");
  if (!ts) return false;
  const std::string& sub = a.words.front();  // the form's keyword
  if (sub == "show") return gainsShow(a, *ts);
  if (sub == "set") return gainsSet(a, *ts);
  if (sub == "push") {
    std::string robot;
    if (a.has("robot")) {
      robot = a.text("robot");
      const auto snap = c_.registry().snapshot(robot, c_.clock().nowNs());
      if (!snap || !snap->connected) return c_.fail("gains", robot + " is not connected");
    } else {
      const auto r = c_.connectedRobot("gains");
      if (!r) return false;
      robot = *r;
    }
    const bool tuned = ts->tuned && control::sameGains(*ts->tuned, ts->working);
    return pushGains(robot, ts->working, tuned ? "tuning session " + ts->tuned_session : "operator console",
                     tuned ? ts->tuned_session : "");
  }
  if (sub == "revert") {
    const std::string robot = a.has("robot") ? a.text("robot") : c_.selected();
    if (robot.empty()) return c_.fail("gains", "no robot selected");
    const auto snap = c_.registry().snapshot(robot, c_.clock().nowNs());
    if (!snap || !snap->connected) return c_.fail("gains", robot + " is not connected");
    if (snap->gains_history.empty()) return c_.fail("gains", robot + ": no earlier gains to go back to");
    const auto& [version, prev] = snap->gains_history.back();
    c_.out() << "gains: reverting " << robot << " to the set of v" << version << "\n";
    if (!pushGains(robot, net::fromProto(prev), "revert to v" + std::to_string(version), "")) return false;
    return true;
  }
  const std::string& file = a.text("file.yaml");
  if (sub == "export") {
    try {
      config::exportGains(ts->working, ts->fis, file, "exported from the pc_server console");
    } catch (const std::exception& e) {
      return c_.fail("gains", e.what());
    }
    c_.out() << "gains: working set written to " << file << " with its fuzzy system beside it\n";
    return true;
  }
  if (sub == "import") {
    fuzzy::Fis fis;
    config::GainsFile f;
    try {
      f = config::importGains(file, ts->working, &fis);
    } catch (const std::exception& e) {
      return c_.fail("gains", e.what());
    }
    ts->working = f.gains;
    if (!f.fis_path.empty()) {
      ts->fis_imported = fuzzy::formatFis(fis) != fuzzy::formatFis(ts->fis) || ts->fis_imported;
      ts->fis = fis;
    }
    c_.out() << "gains: working set from " << file << ": " << gainsText(ts->working) << "\n";
    if (ts->fis_imported) c_.out() << "gains: fuzzy system '" << ts->fis.name << "' goes with the next push\n";
    return true;
  }
  return c_.fail("gains", "unknown subcommand '" + sub + "'");  // a form without its handler
}

}  // namespace inspect::server
