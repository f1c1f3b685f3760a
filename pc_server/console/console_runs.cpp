// The console's commands on recorded runs that read their files back:
// report, export, replay (record/runs/run are in console.cpp).
#include <chrono>
#include <filesystem>

#include "pc_server/console/console.hpp"
#include "pc_server/recording/recorder.hpp"
#include "pc_server/recording/run_report.hpp"
#include "pc_server/scene/topics.hpp"
#include "pc_server/console/status_line.hpp"
#include "pc_server/console/text_util.hpp"
#include "shared/record/csv_export.hpp"
#include "shared/record/mcap_reader.hpp"
#include "shared/world/world.hpp"

namespace inspect::server {

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

/// The run's catalog entry and directory, or prints why not (as `cmd`).
std::optional<std::pair<catalog::RunDetail, std::string>> Console::findRun(const std::string& cmd,
                                                                          const std::string& id) {
  if (!recorder_) {
    fail(cmd, kNoRecorder);
    return std::nullopt;
  }
  auto d = recorder_->catalog().run(id);
  if (!d) {
    fail(cmd, "no run '" + id + "' in the catalog (see runs)");
    return std::nullopt;
  }
  std::string why;
  std::string dir = recorder_->runDir(d->info, &why);
  if (dir.empty()) {
    fail(cmd, why);
    return std::nullopt;
  }
  return std::make_pair(std::move(*d), std::move(dir));
}

bool Console::cmdReport(const CommandArgs& a) {
  const auto run = findRun("report", a.text("run-id"));
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
        out_ << "report: map " << f.path << " not drawn: " << e.what() << "\n";
      }
    }
    const auto r = writeRunReport(in, dir + "/report");
    out_ << d.info.id << ": report " << r.summary_path << " (" << r.pngs.size() << " plots, "
         << log.telemetry.size() << " telemetry messages" << (log.truncated ? ", MCAP cut short" : "") << ")\n";
    for (const auto& p : r.pngs) out_ << "  " << p << "\n";
    for (const auto& l : r.leaks) {
      out_ << "  " << l.channel << ": max " << fmtShort(l.max_value, 2) << " " << l.unit << ", mean "
           << fmtShort(l.mean_value, 2) << " " << l.unit << ", map peak (" << fmtFixed(l.peak_x_m) << ", "
           << fmtFixed(l.peak_y_m) << ")";
      if (l.found)
        out_ << ", leak source estimate (" << fmtFixed(l.x_m) << ", " << fmtFixed(l.y_m) << ") +- "
             << fmtFixed(l.radius95_m) << " m (95 %)";
      else
        out_ << ", no leak source estimate" << (l.note.empty() ? std::string() : ": " + l.note);
      out_ << (in.have_map ? " [world frame]" : " [odometry frame]") << "\n";
    }
    return true;
  } catch (const std::exception& e) {
    return fail("report", d.info.id + ": " + e.what());
  }
}

bool Console::cmdExport(const CommandArgs& a) {
  const auto run = findRun("export", a.text("run-id"));
  if (!run) return false;
  const auto& [d, dir] = *run;
  const std::string out_dir = a.has("dir") ? a.text("dir") : dir + "/csv";
  try {
    const auto r = record::exportCsv(dir + "/run.mcap", out_dir, false, "/" + d.info.robot + "/");
    out_ << d.info.id << ": exported " << r.files.size() << " CSV files to " << out_dir << "\n";
    for (const auto& [topic, path] : r.files)
      out_ << "  " << path << " (" << (r.rows.count(topic) ? r.rows.at(topic) : 0) << " rows)\n";
    return true;
  } catch (const std::exception& e) {
    return fail("export", d.info.id + ": " + e.what());
  }
}

bool Console::cmdReplay(const CommandArgs& a) {
  const double speed = a.number("speed", 1.0);
  const auto run = findRun("replay", a.text("run-id"));
  if (!run) return false;
  const auto& [d, dir] = *run;
  RunLog log;
  try {
    log = readRunLog(dir + "/run.mcap");
  } catch (const std::exception& e) {
    return fail("replay", d.info.id + ": " + e.what());
  }
  if (log.telemetry.empty()) return fail("replay", d.info.id + ": no telemetry recorded");
  out_ << "replaying " << d.info.id << " (" << log.telemetry.size() << " telemetry messages) at " << fmtShort(speed)
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
  const double wall0 = nowS();
  for (std::size_t i = 0; i < log.telemetry.size(); ++i) {
    const double t = static_cast<double>(log.telemetry[i].robot_time_us()) * 1e-6 - t0;
    const double wait_s = t / speed - (nowS() - wall0);
    if (wait_s > 0 && !sleepPumping(wait_s)) return fail("replay", "stopped");
    for (; next_event < log.events.size() && log.events[next_event].first <= t; ++next_event)
      out_ << "[" << fmtFixed(log.events[next_event].first, 2) << " s] " << log.events[next_event].second << "\n";
    if (t >= next_line || i + 1 == log.telemetry.size()) {
      snap.telemetry = log.telemetry[i];
      snap.telemetry.clear_video();  // no live stream behind a replay
      snap.telemetry_hz = 0;
      out_ << "[" << fmtFixed(t, 2) << " s] " << statusLine(d.info.robot, snap) << "\n";
      next_line = t + 1.0;
    }
  }
  out_ << "replay of " << d.info.id << " done\n";
  return true;
}

}  // namespace inspect::server
