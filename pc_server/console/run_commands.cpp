// The console's commands on recorded runs that read their files back:
// report, export, replay; and record, runs, run.
#include <chrono>

#include <filesystem>
#include <map>

#include "pc_server/console/console.hpp"
#include "pc_server/console/run_commands.hpp"
#include "pc_server/console/status_line.hpp"
#include "pc_server/console/text_util.hpp"
#include "pc_server/recording/fleet_presence.hpp"
#include "pc_server/recording/recorder.hpp"
#include "pc_server/recording/run_report.hpp"
#include "pc_server/scene/topics.hpp"
#include "shared/record/csv_export.hpp"
#include "shared/record/mcap_reader.hpp"
#include "shared/world/world.hpp"

namespace inspect::server {

using namespace args;

namespace fs = std::filesystem;

namespace {
constexpr const char* kNoRecorder = "the server records nothing (recording.enabled: false or --no-record)";

struct RunLog {
  std::vector<v1::Telemetry> telemetry;
  std::vector<std::pair<double, std::string>> events;  // s from the first telemetry, text
  std::vector<std::pair<double, v1::GasAlarm>> gas_alarms;  // same clock as events
  std::optional<v1::Hello> hello;                            // /robot_info
  std::vector<uint64_t> telemetry_log_ns;
  bool truncated = false;
};

/// The telemetry and events of a run's MCAP file.
RunLog readRunLog(const std::string& mcap_path) {
  RunLog log;
  auto reader = record::McapReader::open(mcap_path);
  uint64_t t0_us = 0;
  // Topics by the topic table: a run's own names ("/robot1/telemetry") or an
  // older run's ("/telemetry"); docs/recording.md "Topics".
  using scene::TopicKind;
  reader.forEach([&](const record::McapMessageView& m) {
    const auto topic = scene::parseTopic(m.topic);
    if (!topic) return true;
    if (topic->kind == TopicKind::kTelemetry) {
      v1::Telemetry t;
      if (t.ParseFromArray(m.data.data(), static_cast<int>(m.data.size()))) {
        if (log.telemetry.empty()) t0_us = t.robot_time_us();
        log.telemetry.push_back(std::move(t));
        log.telemetry_log_ns.push_back(m.log_time_ns);
      }
    } else if (topic->kind == TopicKind::kEvents || topic->kind == TopicKind::kServerEvents) {
      const bool robots = topic->kind == TopicKind::kEvents;
      v1::Event e;
      if (e.ParseFromArray(m.data.data(), static_cast<int>(m.data.size()))) {
        const double t = robots && t0_us ? (static_cast<double>(e.robot_time_us()) - t0_us) * 1e-6
                         : log.telemetry_log_ns.empty()
                             ? 0.0
                             : (static_cast<double>(m.log_time_ns) - static_cast<double>(log.telemetry_log_ns[0])) * 1e-9;
        log.events.emplace_back(t, (robots ? "" : "server: ") + e.text());
        if (e.has_gas_alarm()) log.gas_alarms.emplace_back(t, e.gas_alarm());
      }
    } else if (topic->kind == TopicKind::kRobotInfo && !log.hello) {
      v1::Hello h;
      if (h.ParseFromArray(m.data.data(), static_cast<int>(m.data.size()))) log.hello = std::move(h);
    }
    return true;
  });
  log.truncated = reader.truncated();
  return log;
}
}  // namespace

std::optional<std::pair<catalog::RunDetail, std::string>> findRun(Console& console, const std::string& cmd,
                                                                  const std::string& id) {
  if (!console.recorder()) {
    console.fail(cmd, kNoRecorder);
    return std::nullopt;
  }
  auto d = console.recorder()->catalog().run(id);
  if (!d) {
    console.fail(cmd, "no run '" + id + "' in the catalog (see runs)");
    return std::nullopt;
  }
  std::string why;
  std::string dir = console.recorder()->runDir(d->info, &why);
  if (dir.empty()) {
    console.fail(cmd, why);
    return std::nullopt;
  }
  return std::make_pair(std::move(*d), std::move(dir));
}

bool RunCommands::cmdReport(const CommandArgs& a) {
  const auto run = findRun(c_, "report", a.text("run-id"));
  if (!run) return false;
  const auto& [d, dir] = *run;
  try {
    const auto log = readRunLog(dir + "/run.mcap");
    RunReportInput in;
    in.run_id = d.info.id;
    in.robot = d.info.robot;
    in.name = d.info.name;
    in.outcome = d.info.outcome.empty() ? "running" : d.info.outcome;
    in.started_utc = catalog::formatIsoUtc(d.info.start);
    in.ended_utc = d.info.end ? catalog::formatIsoUtc(*d.info.end) : "";
    in.telemetry = log.telemetry;
    in.events = log.events;
    in.gas_alarms = log.gas_alarms;
    if (log.hello) {
      in.gas_channels.assign(log.hello->gas_channels().begin(), log.hello->gas_channels().end());
      in.gas_inlet_x_m = log.hello->gas_inlet_x_m();
      in.gas_inlet_y_m = log.hello->gas_inlet_y_m();
    }
    for (const auto& f : d.files) {
      in.files.push_back(f.path);
      if (f.kind != "map" || in.have_map) continue;
      // The site map of an inspection route: walls and obstacle edges in the world frame.
      try {
        const auto w = world::loadWorldFile(f.path);
        for (const auto& e : world::solidEdges(w)) in.walls.push_back(e.edge);
        in.have_map = true;
        in.start_x_m = w.start.x_m;
        in.start_y_m = w.start.y_m;
        in.start_theta_rad = w.start.theta_rad;
        in.map_name = w.name;
      } catch (const std::exception& e) {
        c_.out() << "report: map " << f.path << " not drawn: " << e.what() << "\n";
      }
    }
    const auto r = writeRunReport(in, dir + "/report");
    c_.out() << d.info.id << ": report " << r.summary_path << " (" << r.pngs.size() << " plots, "
         << log.telemetry.size() << " telemetry messages" << (log.truncated ? ", MCAP cut short" : "") << ")\n";
    for (const auto& p : r.pngs) c_.out() << "  " << p << "\n";
    for (const auto& l : r.leaks) {
      c_.out() << "  " << l.channel << ": max " << fmtShort(l.max_value, 2) << " " << l.unit << ", mean "
           << fmtShort(l.mean_value, 2) << " " << l.unit << ", map peak (" << fmtFixed(l.peak_x_m) << ", "
           << fmtFixed(l.peak_y_m) << ")";
      if (l.found)
        c_.out() << ", leak source estimate (" << fmtFixed(l.x_m) << ", " << fmtFixed(l.y_m) << ") +- "
             << fmtFixed(l.radius95_m) << " m (95 %)";
      else
        c_.out() << ", no leak source estimate" << (l.note.empty() ? std::string() : ": " + l.note);
      c_.out() << (in.have_map ? " [world frame]" : " [odometry frame]") << "\n";
    }
    return true;
  } catch (const std::exception& e) {
    return c_.fail("report", d.info.id + ": " + e.what());
  }
}

bool RunCommands::cmdExport(const CommandArgs& a) {
  const auto run = findRun(c_, "export", a.text("run-id"));
  if (!run) return false;
  const auto& [d, dir] = *run;
  const std::string out_dir = a.has("dir") ? a.text("dir") : dir + "/csv";
  try {
    const auto r = record::exportCsv(dir + "/run.mcap", out_dir, false, "/" + d.info.robot + "/");
    c_.out() << d.info.id << ": exported " << r.files.size() << " CSV files to " << out_dir << "\n";
    for (const auto& [topic, path] : r.files)
      c_.out() << "  " << path << " (" << (r.rows.count(topic) ? r.rows.at(topic) : 0) << " rows)\n";
    return true;
  } catch (const std::exception& e) {
    return c_.fail("export", d.info.id + ": " + e.what());
  }
}

bool RunCommands::cmdReplay(const CommandArgs& a) {
  const double speed = a.number("speed", 1.0);
  const auto run = findRun(c_, "replay", a.text("run-id"));
  if (!run) return false;
  const auto& [d, dir] = *run;
  RunLog log;
  try {
    log = readRunLog(dir + "/run.mcap");
  } catch (const std::exception& e) {
    return c_.fail("replay", d.info.id + ": " + e.what());
  }
  if (log.telemetry.empty()) return c_.fail("replay", d.info.id + ": no telemetry recorded");
  c_.out() << "replaying " << d.info.id << " (" << log.telemetry.size() << " telemetry messages) at " << fmtShort(speed)
       << "x; status lines every second of run time\n";
  // The status line as it was, once per second of run time (and events as they came).
  RobotSnapshot snap;
  snap.id = d.info.robot;
  snap.connected = true;
  snap.has_telemetry = true;
  if (log.hello) snap.hello = *log.hello;  // the gas channels' names, as the live line shows them
  const double t0 = static_cast<double>(log.telemetry.front().robot_time_us()) * 1e-6;
  double next_line = 0;
  std::size_t next_event = 0;
  const double wall0 = c_.nowS();
  for (std::size_t i = 0; i < log.telemetry.size(); ++i) {
    const double t = static_cast<double>(log.telemetry[i].robot_time_us()) * 1e-6 - t0;
    const double wait_s = t / speed - (c_.nowS() - wall0);
    if (wait_s > 0 && !c_.sleepPumping(wait_s)) return c_.fail("replay", "stopped");
    for (; next_event < log.events.size() && log.events[next_event].first <= t; ++next_event)
      c_.out() << "[" << fmtFixed(log.events[next_event].first, 2) << " s] " << log.events[next_event].second << "\n";
    if (t >= next_line || i + 1 == log.telemetry.size()) {
      snap.telemetry = log.telemetry[i];
      snap.telemetry.clear_video();  // no live stream behind a replay
      snap.telemetry_hz = 0;
      c_.out() << "[" << fmtFixed(t, 2) << " s] " << statusLine(d.info.robot, snap) << "\n";
      next_line = t + 1.0;
    }
  }
  c_.out() << "replay of " << d.info.id << " done\n";
  return true;
}

bool RunCommands::cmdRecord(const CommandArgs& a) {
  if (!c_.recorder()) return c_.fail("record", kNoRecorder);
  const CallResult r = a.has("stop") ? c_.service().recordStop(c_.session(), c_.selected())
                                     : c_.service().recordStart(c_.session(), c_.selected(), a.text("name"));
  if (!r.ok()) return c_.fail("record", r.reason);
  c_.out() << r.robot << ": " << r.reason << "\n";
  return true;
}

bool RunCommands::cmdRuns(const CommandArgs& args) {
  if (!c_.recorder()) return c_.fail("runs", kNoRecorder);
  catalog::RunFilter f;
  f.limit = 20;
  const bool fleet = args.has("--fleet");
  auto& cat = c_.recorder()->catalog();
  if (!fleet) f.server = cat.serverId();  // "" = every run (a catalog of one server)
  for (const auto& a : args.list("words")) {
    if (const auto n = parseInteger(a); n && *n > 0) {
      f.limit = static_cast<int>(*n);
    } else if (a == "completed" || a == "stopped" || a == "failed" || a == "incomplete" || a == "running") {
      f.outcome = a;
    } else if (c_.registry().snapshot(a, c_.clock().nowNs())) {
      f.robot = a;
    } else {
      f.name_contains = a;
    }
  }
  const auto runs = cat.listRuns(f);
  std::map<std::string, std::string> attach;  // server id -> where to attach
  if (fleet)
    for (const auto& sv : cat.listServers()) attach[sv.id] = sv.attach;
  c_.out() << padRight("run", 28) << padRight("robot", 10) << padRight("started (UTC)", 26) << padRight("outcome", 12)
       << (fleet ? padRight("server", 22) : "") << "name\n";
  for (const auto& r : runs) {
    std::string server;
    if (fleet) {
      server = r.server.empty() ? "-" : r.server;
      if (const auto at = attach.find(r.server); at != attach.end() && !at->second.empty()) server += " @" + at->second;
    }
    c_.out() << padRight(r.id, 28) << padRight(r.robot, 10) << padRight(catalog::formatIsoUtc(r.start), 26)
         << padRight(r.outcome.empty() ? "running" : r.outcome, 12) << (fleet ? padRight(server, 22) : "") << r.name
         << "\n";
  }
  c_.out() << runs.size() << " run" << (runs.size() == 1 ? "" : "s") << "\n";
  return true;
}

bool RunCommands::cmdRun(const CommandArgs& a) {
  if (!c_.recorder()) return c_.fail("run", kNoRecorder);
  const auto d = c_.recorder()->catalog().run(a.text("run-id"));
  if (!d) return c_.fail("run", "no run '" + a.text("run-id") + "' in the catalog (see runs)");
  const auto& i = d->info;
  c_.out() << "run " << i.id << " (" << i.robot << ")" << (i.name.empty() ? "" : ": " + i.name) << "\n";
  c_.out() << "  started " << catalog::formatIsoUtc(i.start)
       << (i.end ? ", ended " + catalog::formatIsoUtc(*i.end) : std::string(", still recording"))
       << (i.outcome.empty() ? "" : ", " + i.outcome) << "\n";
  if (d->summary) {
    const auto& s = *d->summary;
    c_.out() << "  duration " << fmtFixed(s.duration_s, 1) << " s, distance " << fmtFixed(s.distance_m, 2) << " m"
         << (s.min_person_m ? ", nearest person " + fmtFixed(*s.min_person_m, 2) + " m" : std::string()) << "\n";
    if (s.track_max_pos_err_m)
      c_.out() << "  tracking: max position error " << fmtFixed(*s.track_max_pos_err_m, 3) << " m, rms "
           << fmtFixed(s.track_rms_pos_err_m.value_or(0), 3) << " m, max angle error "
           << fmtFixed(s.track_max_angle_err_rad.value_or(0), 3) << " rad\n";
    c_.out() << "  video: " << s.video_frames_received << " frames received, " << s.video_frames_decoded
         << " decoded, " << s.video_packets_lost << " packets lost\n";
    for (const auto& g : s.gas)
      c_.out() << "  " << g.channel << ": max " << fmtShort(g.max, 3) << " mean " << fmtShort(g.mean, 3) << " " << g.unit
           << "\n";
  }
  c_.out() << "  events " << d->event_count << ", alarms " << d->alarm_count << "\n";
  for (const auto& f : d->files) c_.out() << "  " << f.kind << ": " << f.path << " (" << f.bytes << " bytes)\n";
  return true;
}

// Commands of recorded runs (docs/recording.md).
std::vector<ConsoleCommand> RunCommands::commands() {
  return {
    {"record", {{subcommand("start"), opt(rest("name"))}, {keyword("stop")}}, "record a run of the selected robot",
     "  A run is written to <recording.dir>/<run-id>/: run.mcap (telemetry, commands, acks, events,\n"
     "  camera frames; Foxglove opens it) and video.mp4, and listed in catalog.sqlite with its\n"
     "  summary. track, goto and route start one by themselves (recording.auto_start) and end it\n"
     "  when they complete or fail; record stop ends it ('stopped'). The status line shows REC.\n"
     "  example: record start night round B\n",
     handler(this, &RunCommands::cmdRecord)},
    {"runs", {{keyword("--fleet"), words("[robot|outcome|text] [limit]")}, {words("[robot|outcome|text] [limit]")}},
     "list recorded runs, newest first",
     "  A filter word is a robot id, an outcome (completed, stopped, failed, incomplete,\n"
     "  running) or text in the run's name. Default limit 20.\n"
     "  With a catalog that several servers share (--catalog postgresql://...), the runs of\n"
     "  this server; --fleet: every server's, with the server and where to attach to it.\n"
     "  example: runs robot1\n"
     "  example: runs --fleet incomplete\n",
     handler(this, &RunCommands::cmdRuns)},
    {"run", {{subcommand("show"), word("run-id")}}, "a recorded run's summary, files and counts",
     "  example: run show 20261122-083015-robot1\n", handler(this, &RunCommands::cmdRun)},
    {"report", {{word("run-id")}}, "write a run's report: PNG plots and summary.md in <run>/report/",
     "  Plots: trajectory (with the tracking reference), speed and nearest person with the proxemic\n"
     "  zones, tracking errors, gas concentrations; summary.md links them and the run's files.\n"
     "  example: report 20261122-083015-robot1\n",
     handler(this, &RunCommands::cmdReport)},
    {"export", {{word("run-id"), keyword("csv"), opt(word("dir"))}}, "one CSV per channel of a run's MCAP file (default <run>/csv/)",
     "  Columns: log_time_s, publish_time_s, then every field, nested ones dotted (pose.x_m).\n",
     handler(this, &RunCommands::cmdExport)},
    {"replay", {{word("run-id"), opt(within(number("speed"), 0.1, 100))}}, "play a run's telemetry back as status lines (speed 0.1-100, default 1)",
     "  One status line per second of run time, and the run's events as they came.\n"
     "  example: replay 1 10\n",
     handler(this, &RunCommands::cmdReplay)},
  };
}

}  // namespace inspect::server
