#include "pc_server/console/console.hpp"

#include "shared/net/robot_id.hpp"

#include <chrono>
#include <cmath>
#include <map>
#include <cstdio>
#include <variant>

#include "pc_server/console/expect_check.hpp"
#include "pc_server/link/hello_check.hpp"
#include "pc_server/operator/route_file.hpp"
#include "pc_server/console/status_line.hpp"
#include "pc_server/console/text_util.hpp"
#include "pc_server/recording/fleet_presence.hpp"
#include "pc_server/recording/recorder.hpp"
#include "pc_server/video/video_hub.hpp"
#include "shared/config/config_node.hpp"
#include "shared/util/clock.hpp"

namespace inspect::server {

namespace {
/// Removes a comment: '#' at the start or after a blank.
std::string stripComment(const std::string& line) {
  for (std::size_t i = 0; i < line.size(); ++i)
    if (line[i] == '#' && (i == 0 || line[i - 1] == ' ' || line[i - 1] == '\t')) return line.substr(0, i);
  return line;
}
}  // namespace

Console::Console(RobotRegistry& registry, CommandSink& sink, std::ostream& out, StopFlag& stop)
    : Console(registry, sink, out, stop, Options{}) {}

Console::Console(RobotRegistry& registry, CommandSink& sink, std::ostream& out, StopFlag& stop, Options options)
    : registry_(registry), sink_(sink), out_(out), stop_(stop), options_(options) {
  setSession(nullptr, 0);
}

void Console::setSession(ControlArbiter* arbiter, uint64_t session) {
  control_ = arbiter;
  session_ = session;
  service_.emplace(registry_, sink_, arbiter,
                   OperatorService::Options{options_.ack_timeout_s, options_.max_v_m_s, options_.max_w_rad_s});
  service_->setRunContext(recorder_, site_maps_);
}

bool Console::fail(const std::string& cmd, const std::string& message) {
  out_ << cmd << ": " << message << "\n";
  ++tally_.errors;
  return false;
}

bool Console::execute(const std::string& raw_line, int line_no) {
  out_ << background();
  const std::string line = trim(stripComment(raw_line));
  if (line.empty()) return true;
  const auto words = splitWords(line);
  const std::string& name = words.front();
  if (name == "try") {
    // 'try <command>': run it, but a failure (an error, a rejection, a failed
    // expect) does not count against the script; for checks that a command is refused.
    if (words.size() < 2) return fail("try", "needs a command: try <command>");
    const Tally before = tally_;
    const bool ok = execute(trim(line.substr(3)), line_no);
    if (!ok) {
      tally_.errors = before.errors;
      tally_.expects_failed = before.expects_failed;
      out_ << "(try: failure allowed)\n";
    }
    return true;
  }
  ++tally_.commands;
  const CommandDef* c = findCommand(name == "?" ? "help" : name);
  if (!c) {
    out_ << "unknown command '" << name << "' (try 'help')\n";
    ++tally_.errors;
    return false;
  }
  const std::size_t at = line.find_first_of(" \t", 0);
  auto parsed = parseCommandArgs(c->name, c->forms, at == std::string::npos ? "" : line.substr(at));
  if (auto* why = std::get_if<std::string>(&parsed)) return fail(c->name, *why);
  auto& args = std::get<CommandArgs>(parsed);
  args.line_no = line_no;
  bool ok = false;
  try {
    ok = (this->*(c->run))(args);
  } catch (const catalog::CatalogUnavailable& e) {  // runs, run, report... while a shared catalog is away
    const auto st = recorder_ ? recorder_->catalogStatus() : catalog::SpoolStatus{};
    ok = fail(c->name, std::string(e.what()) + " (recording goes on; " + std::to_string(st.pending) +
                           " catalog writes kept until it is back)");
  } catch (const std::exception& e) {
    ok = fail(c->name, e.what());
  }
  out_.flush();
  return ok;
}

std::string Console::background() {
  if (options_.feeds_watchdog) sink_.consoleAlive();
  std::string s;
  if (selected_.empty()) {
    if (auto first = registry_.firstConnected(); !first.empty()) {
      selected_ = first;
      s += "selected " + first + " (the first robot to connect)\n";
    }
  }
  if (control_)
    for (const auto& note : control_->takeNotes(session_)) s += note + "\n";
  uint64_t missed = 0;
  const auto events = registry_.eventsSince(event_cursor_, &missed);
  if (missed > 0) s += "(" + std::to_string(missed) + " robot events missed: this console fell behind)\n";
  for (const auto& e : events) {
    const std::string line = "[" + e.robot_id + "] " + v1::Event::Kind_Name(e.event.kind()) + ": " + e.event.text();
    if (e.event.kind() == v1::Event::ALARM_RAISED && alarm_style_)
      s += "\a\x1b[1;31m" + line + "\x1b[0m\n";  // red, with the terminal bell
    else
      s += line + "\n";
  }
  // The catalog went away or came back (the spool): every console says so.
  if (recorder_)
    for (const auto& note : recorder_->catalogNotices(catalog_notices_)) s += note + "\n";
  for (auto it = runs_.begin(); it != runs_.end();) {
    const auto a = registry_.ack(it->robot_id, it->command_id);
    if (a && a->status() == v1::Ack::COMPLETED) {
      s += it->robot_id + ": " + it->name + " completed\n";
      it = runs_.erase(it);
    } else if (a && a->status() == v1::Ack::FAILED) {
      s += it->robot_id + ": " + it->name + " failed: " + a->reason() + "\n";
      it = runs_.erase(it);
    } else {
      ++it;
    }
  }
  return s;
}

void Console::pump() {
  out_ << background();
  out_.flush();
  if (idle_hook_) idle_hook_();
}

bool Console::sleepPumping(double s) {
  const int64_t deadline = deadlineAfter(s);
  for (;;) {
    pump();
    const int64_t left_ns = deadline - clock_->nowNs();
    if (left_ns <= 0) return true;
    if (!clock_->sleep(std::min(static_cast<double>(left_ns) * 1e-9, options_.poll_period_s))) return false;
  }
}

bool Console::mayMove(const std::string& robot, const std::string& cmd) {
  std::string note;
  const auto refused = service_->authorize(session_, robot, cmd, clock_->nowNs(), &note);
  if (!note.empty()) out_ << note << "\n";
  if (!refused) return true;
  out_ << refused->text() << "\n";
  ++tally_.errors;
  return false;
}

bool Console::cmdControl(const CommandArgs& a) {
  if (!control_) return fail("control", "this console has no sessions (no control arbiter)");
  if (a.form == 0) {
    out_ << "this session: " << control_->sessionName(session_) << "\n";
    const auto holders = control_->holders();
    for (const auto& snap : registry_.snapshots(clock_->nowNs())) {
      const auto it = holders.find(snap.id);
      out_ << "  " << snap.id << (snap.connected ? "" : " (not connected)") << ": "
           << (it == holders.end() ? std::string("free")
                                   : it->second.name + (it->second.session == session_ ? " <- this session" : ""))
           << "\n";
    }
    return true;
  }
  const auto r = a.has("release") ? service_->releaseControl(session_, selected_)
                                  : service_->takeControl(session_, selected_, a.has("force"), clock_->nowNs());
  if (!r.ok()) return fail("control", r.reason);
  out_ << r.robot << ": " << r.reason << "\n";
  return true;
}

std::optional<std::string> Console::connectedRobot(const std::string& cmd) {
  if (selected_.empty()) {
    fail(cmd, "no robot selected");
    return std::nullopt;
  }
  const auto snap = registry_.snapshot(selected_, clock_->nowNs());
  if (!snap || !snap->connected) {
    fail(cmd, selected_ + " is not connected");
    return std::nullopt;
  }
  return selected_;
}

CallResult Console::await(const PendingCall& pending) {
  WakeSignal& arrived = service_->ackSignal();
  for (;;) {
    const uint64_t seen = arrived.generation();  // before looking: an Ack after the look moves it
    const int64_t now = clock_->nowNs();
    if (auto r = service_->settle(pending, now)) return *r;
    pump();
    // Woken by the Ack itself (a millisecond or two on a working link, so
    // 'drive' + 'wait T' stays close to T of motion); the console's status
    // line and events are pumped at least every ack_pump_period_s meanwhile.
    const double left_s = static_cast<double>(pending.deadline_ns - now) * 1e-9;
    if (!clock_->waitSignal(std::min(left_s, options_.ack_pump_period_s), arrived, seen))
      return *service_->settle(pending, std::max(now, pending.deadline_ns));  // the server stops
  }
}

CallResult Console::outcomeOf(const Issued& issued) {
  if (const auto* done = std::get_if<CallResult>(&issued)) return *done;
  const auto& pending = std::get<PendingCall>(issued);
  if (!pending.control_note.empty()) out_ << pending.control_note << "\n";
  return await(pending);
}

bool Console::report(const Issued& issued, bool runs) {
  const CallResult r = outcomeOf(issued);
  if (r.outcome == CallOutcome::kInvalid) return fail(r.action, r.reason);
  out_ << r.text() << "\n";
  if (!r.ok()) {
    ++tally_.errors;
    return false;
  }
  if (runs && r.outcome == CallOutcome::kAccepted) {
    // One run per robot: a new one ends the previous (the robot does the same).
    std::erase_if(runs_, [&](const Run& run) { return run.robot_id == r.robot; });
    runs_.push_back({r.robot, r.command_id, r.action});
  }
  return true;
}

bool Console::cmdHelp(const CommandArgs& a) {
  if (!a.has("command")) {
    out_ << helpText();
    return true;
  }
  const std::string text = helpText(a.text("command"));
  if (text.empty()) return fail("help", "unknown command '" + a.text("command") + "'");
  out_ << text;
  return true;
}

bool Console::cmdRobots(const CommandArgs& a) {
  if (a.has("--fleet")) {
    if (!recorder_) return fail("robots", "--fleet reads the catalog, and this server records nothing (--no-record)");
    auto& cat = recorder_->catalog();
    if (cat.serverId().empty())
      return fail("robots", "--fleet needs a catalog that several servers share (--catalog postgresql://...); "
                            "this server's robots are 'robots'");
    out_ << fleetTable(cat.listPresence(), cat.listServers(), std::chrono::system_clock::now());
    return true;
  }
  const auto all = registry_.snapshots(clock_->nowNs());
  if (all.empty()) {
    out_ << "no robot has connected yet\n";
    return true;
  }
  out_ << "  " << padRight("id", 16) << " " << padRight("connected", 9) << " " << padRight("address", 21) << " "
       << padLeft("tlm Hz", 6) << " " << padRight("mode", 9) << " " << padLeft("tlm age", 8) << "\n";
  for (const auto& r : all) {
    const std::string age = r.has_telemetry ? fmtFixed(r.telemetry_age_s, 2) + " s" : "-";
    const std::string mode = r.has_telemetry ? modeName(r.telemetry.mode()) : "-";
    out_ << (r.id == selected_ ? "* " : "  ") << padRight(r.id, 16) << " " << padRight(r.connected ? "yes" : "no", 9)
         << " " << padRight(r.address, 21) << " " << padLeft(fmtFixed(r.telemetry_hz, 1), 6) << " "
         << padRight(mode, 9) << " " << padLeft(age, 8) << "\n";
  }
  return true;
}

bool Console::cmdSelect(const CommandArgs& a) { return select(a.text("robot")); }

bool Console::select(const std::string& robot) {
  if (!net::validRobotId(robot)) return fail("select", "'" + robot + "' is not a valid robot id ([A-Za-z0-9_-]{1,64})");
  selected_ = robot;
  const auto snap = registry_.snapshot(selected_, clock_->nowNs());
  out_ << "selected " << selected_ << (snap && snap->connected ? "" : " (not connected yet)") << "\n";
  return true;
}

bool Console::cmdStatus(const CommandArgs& a) {
  const std::string robot = a.has("robot") ? a.text("robot") : selected_;
  if (robot.empty()) return fail("status", "no robot selected");
  out_ << statusText(robot) << "\n";
  return true;
}

std::string Console::statusText(const std::string& robot) const {
  std::string s = statusLine(robot, registry_.snapshot(robot, clock_->nowNs()), video_);
  if (recorder_)
    if (const auto run = recorder_->activeRun(robot)) s += " | REC " + *run;
  return s;
}

bool Console::cmdRecord(const CommandArgs& a) {
  if (!recorder_) return fail("record", "the server records nothing (recording.enabled: false or --no-record)");
  const CallResult r = a.has("stop") ? service_->recordStop(session_, selected_)
                                     : service_->recordStart(session_, selected_, a.text("name"));
  if (!r.ok()) return fail("record", r.reason);
  out_ << r.robot << ": " << r.reason << "\n";
  return true;
}

bool Console::cmdRuns(const CommandArgs& args) {
  if (!recorder_) return fail("runs", "the server records nothing (recording.enabled: false or --no-record)");
  catalog::RunFilter f;
  f.limit = 20;
  const bool fleet = args.has("--fleet");
  auto& cat = recorder_->catalog();
  if (!fleet) f.server = cat.serverId();  // "" = every run (a catalog of one server)
  for (const auto& a : args.list("words")) {
    if (const auto n = parseInteger(a); n && *n > 0) {
      f.limit = static_cast<int>(*n);
    } else if (a == "completed" || a == "stopped" || a == "failed" || a == "incomplete" || a == "running") {
      f.outcome = a;
    } else if (registry_.snapshot(a, clock_->nowNs())) {
      f.robot = a;
    } else {
      f.name_contains = a;
    }
  }
  const auto runs = cat.listRuns(f);
  std::map<std::string, std::string> attach;  // server id -> where to attach
  if (fleet)
    for (const auto& sv : cat.listServers()) attach[sv.id] = sv.attach;
  out_ << padRight("run", 28) << padRight("robot", 10) << padRight("started (UTC)", 26) << padRight("outcome", 12)
       << (fleet ? padRight("server", 22) : "") << "name\n";
  for (const auto& r : runs) {
    std::string server;
    if (fleet) {
      server = r.server.empty() ? "-" : r.server;
      if (const auto at = attach.find(r.server); at != attach.end() && !at->second.empty()) server += " @" + at->second;
    }
    out_ << padRight(r.id, 28) << padRight(r.robot, 10) << padRight(catalog::formatIsoUtc(r.start), 26)
         << padRight(r.outcome.empty() ? "running" : r.outcome, 12) << (fleet ? padRight(server, 22) : "") << r.name
         << "\n";
  }
  out_ << runs.size() << " run" << (runs.size() == 1 ? "" : "s") << "\n";
  return true;
}

bool Console::cmdRun(const CommandArgs& a) {
  if (!recorder_) return fail("run", "the server records nothing (recording.enabled: false or --no-record)");
  const auto d = recorder_->catalog().run(a.text("run-id"));
  if (!d) return fail("run", "no run '" + a.text("run-id") + "' in the catalog (see runs)");
  const auto& i = d->info;
  out_ << "run " << i.id << " (" << i.robot << ")" << (i.name.empty() ? "" : ": " + i.name) << "\n";
  out_ << "  started " << catalog::formatIsoUtc(i.start)
       << (i.end ? ", ended " + catalog::formatIsoUtc(*i.end) : std::string(", still recording"))
       << (i.outcome.empty() ? "" : ", " + i.outcome) << "\n";
  if (d->summary) {
    const auto& s = *d->summary;
    out_ << "  duration " << fmtFixed(s.duration_s, 1) << " s, distance " << fmtFixed(s.distance_m, 2) << " m"
         << (s.min_person_m ? ", nearest person " + fmtFixed(*s.min_person_m, 2) + " m" : std::string()) << "\n";
    if (s.track_max_pos_err_m)
      out_ << "  tracking: max position error " << fmtFixed(*s.track_max_pos_err_m, 3) << " m, rms "
           << fmtFixed(s.track_rms_pos_err_m.value_or(0), 3) << " m, max angle error "
           << fmtFixed(s.track_max_angle_err_rad.value_or(0), 3) << " rad\n";
    out_ << "  video: " << s.video_frames_received << " frames received, " << s.video_frames_decoded
         << " decoded, " << s.video_packets_lost << " packets lost\n";
    for (const auto& g : s.gas)
      out_ << "  " << g.channel << ": max " << fmtShort(g.max, 3) << " mean " << fmtShort(g.mean, 3) << " " << g.unit
           << "\n";
  }
  out_ << "  events " << d->event_count << ", alarms " << d->alarm_count << "\n";
  for (const auto& f : d->files) out_ << "  " << f.kind << ": " << f.path << " (" << f.bytes << " bytes)\n";
  return true;
}

bool Console::cmdWait(const CommandArgs& a) {
  if (!sleepPumping(*a.number("seconds"))) return fail("wait", "interrupted (server stopping)");
  return true;
}

bool Console::cmdExpect(const CommandArgs& a) {
  const int line_no = a.line_no;
  const auto parsed = parseExpect(a.words);
  if (const auto* err = std::get_if<std::string>(&parsed)) {
    out_ << "EXPECT FAILED (line " << line_no << "): " << *err << "\n";
    ++tally_.expects_failed;
    return false;
  }
  const auto& spec = std::get<ExpectSpec>(parsed);
  const int64_t deadline = deadlineAfter(spec.within_s);
  FieldReading r;
  bool interrupted = false;
  for (;;) {
    r = readField(spec.field, registry_, selected_, clock_->nowNs());
    if (satisfied(spec, r)) {
      out_ << "expect ok (line " << line_no << "): " << spec.field << " = " << r.text << "\n";
      ++tally_.expects_passed;
      return true;
    }
    if (clock_->nowNs() >= deadline) break;
    pump();
    if (!clock_->sleep(options_.poll_period_s)) {
      interrupted = true;
      break;
    }
  }
  out_ << "EXPECT FAILED (line " << line_no << "): " << spec.field;
  if (r.ok) out_ << " = " << r.text;
  else out_ << ": " << r.error;
  out_ << ", wanted " << describeWanted(spec) << (interrupted ? " (interrupted)" : "") << "\n";
  ++tally_.expects_failed;
  return false;
}

bool Console::cmdEcho(const CommandArgs& a) {
  out_ << a.rest << "\n";
  return true;
}

bool Console::cmdQuit(const CommandArgs&) {
  quit_ = true;
  return true;
}

}  // namespace inspect::server
