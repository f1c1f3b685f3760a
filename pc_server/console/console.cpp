// The Console's core: a line parsed against the command table of the
// registered families, its handler run; between commands the robot events,
// control notes, catalog notices and completed runs; the waits and answers
// every family shares (console.hpp, "For the command families").
#include "pc_server/console/console.hpp"

#include <cmath>
#include <variant>

#include "pc_server/console/gas_commands.hpp"
#include "pc_server/console/motion_commands.hpp"
#include "pc_server/console/run_commands.hpp"
#include "pc_server/console/script_commands.hpp"
#include "pc_server/console/session_commands.hpp"
#include "pc_server/console/status_line.hpp"
#include "pc_server/console/text_util.hpp"
#include "pc_server/console/tuning_commands.hpp"
#include "pc_server/recording/recorder.hpp"
#include "shared/catalog/catalog.hpp"
#include "shared/net/robot_id.hpp"

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
  // The command families, in the order help lists them.
  families_.push_back(std::make_unique<SessionCommands>(*this));
  families_.push_back(std::make_unique<MotionCommands>(*this));
  families_.push_back(std::make_unique<GasCommands>(*this));
  auto tuning = std::make_unique<TuningCommands>(*this);
  tuning_ = tuning.get();
  families_.push_back(std::move(tuning));
  families_.push_back(std::make_unique<RunCommands>(*this));
  families_.push_back(std::make_unique<ScriptCommands>(*this));
  for (const auto& family : families_)
    for (auto& c : family->commands()) table_.push_back(std::move(c));
}

Console::~Console() = default;

void Console::setTuningPaths(std::string robot_config, std::string control_config, std::string dir) {
  tuning_->setPaths(std::move(robot_config), std::move(control_config), std::move(dir));
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
  const ConsoleCommand* c = findCommand(name == "?" ? "help" : name);
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
    ok = c->run(args);
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

void Console::operatorPresent() { service_->renewTeleop(session_, drive_robot_, options_.drive_lease_s); }

bool Console::sendAndReport(const std::string& name, v1::Command cmd, bool runs) {
  return report(service_->send(session_, selected_, name, std::move(cmd), clock_->nowNs()), runs);
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

bool Console::select(const std::string& robot) {
  if (!net::validRobotId(robot)) return fail("select", "'" + robot + "' is not a valid robot id ([A-Za-z0-9_-]{1,64})");
  selected_ = robot;
  const auto snap = registry_.snapshot(selected_, clock_->nowNs());
  out_ << "selected " << selected_ << (snap && snap->connected ? "" : " (not connected yet)") << "\n";
  return true;
}

std::string Console::statusText(const std::string& robot) const {
  std::string s = statusLine(robot, registry_.snapshot(robot, clock_->nowNs()), video_);
  if (recorder_)
    if (const auto run = recorder_->activeRun(robot)) s += " | REC " + *run;
  return s;
}

}  // namespace inspect::server
