#include "pc_server/console/console.hpp"

#include "shared/net/robot_id.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <variant>

#include "pc_server/console/expect_check.hpp"
#include "pc_server/link/hello_check.hpp"
#include "pc_server/console/route_file.hpp"
#include "pc_server/console/status_line.hpp"
#include "pc_server/console/text_util.hpp"
#include "pc_server/recording/recorder.hpp"
#include "pc_server/video/video_hub.hpp"
#include "shared/config/config_node.hpp"
#include "shared/util/clock.hpp"

namespace inspect::server {

namespace {
std::string padRight(std::string s, std::size_t w) {
  if (s.size() < w) s.append(w - s.size(), ' ');
  return s;
}
std::string padLeft(std::string s, std::size_t w) {
  if (s.size() < w) s.insert(0, w - s.size(), ' ');
  return s;
}

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
    : registry_(registry), sink_(sink), out_(out), stop_(stop), options_(options) {}

const std::vector<Console::CommandDef>& Console::commands() {
  static const std::vector<CommandDef> kCommands = {
      {"help", "help [command]", "list the commands, or explain one",
       "  help          lists every command\n"
       "  help drive    explains one command\n",
       &Console::cmdHelp},
      {"robots", "robots", "table of robots: id, connected, address, telemetry Hz, mode, telemetry age",
       "  Lists every robot that connected since the server started; '*' marks the selected one.\n",
       &Console::cmdRobots},
      {"select", "select <robot>", "choose the robot that drive/stop/estop/resume/status/expect act on",
       "  The robot need not be connected yet. With no selection, the first robot to connect\n"
       "  is selected automatically.\n"
       "  example: select robot2\n",
       &Console::cmdSelect},
      {"status", "status [robot]", "one status line of the selected (or named) robot",
       "  example: status\n"
       "  robot1 | TELEOP | v +0.30 w +0.00 | x 1.20 y 0.00 th +0.00 | us 1.23 2.01 -- 0.88 | faults none |"
       " tlm 50 Hz | serial ok\n",
       &Console::cmdStatus},
      {"drive", "drive <v_m_s> <w_rad_s>", "set the teleop set-point; re-sent at teleop_resend_hz until stop",
       "  v in [-1, 1] m/s (forward positive), w in [-2, 2] rad/s (counter-clockwise positive).\n"
       "  The server re-sends the set-point (default 20 Hz) so the robot's 300 ms deadman stays\n"
       "  quiet while the console and link work. Waits up to 1 s for the robot's Ack of the first\n"
       "  command; a rejection or no Ack clears the set-point and is an error.\n"
       "  example: drive 0.3 0      (straight ahead at 0.3 m/s)\n"
       "  example: drive 0 0.5      (turn on the spot, 0.5 rad/s to the left)\n",
       &Console::cmdDrive},
      {"teleop", "teleop [step|hold]", "keyboard teleop (interactive terminal only)",
       "  step (default): w/s or Up/Down step v by 0.05 m/s, a/d or Left/Right step w by 0.1 rad/s\n"
       "    (clamped to +-1.0 m/s, +-2.0 rad/s); the set-point stays until changed.\n"
       "  hold: hold w/s/a/d (or arrows) to drive at 0.3 m/s or 1.0 rad/s; releasing the key\n"
       "    zeroes the set-point (deadman: 600 ms before the first auto-repeat, 200 ms after).\n"
       "  Both: space (or x, 0) zeroes at once; q or Esc leaves teleop and sends stop.\n",
       &Console::cmdTeleop},
      {"track", "track circle <radius_m> [speed_m_s] [laps] [controller] | track line <length_m> [speed_m_s] [controller]",
       "track a reference path from the robot's current pose (Eqs 10-15)",
       "  circle: radius > 0 turns left (counter-clockwise), < 0 right; speed default 0.5 m/s, laps 1.\n"
       "  line: straight ahead. controller: fuzzy_pid, pid or direct (default: the robot's config).\n"
       "  Waits for the Ack; the robot acks again (COMPLETED) when the path is done and goes IDLE.\n"
       "  Telemetry then carries the reference pose and the errors (expect pos_err, max_pos_err, ...).\n"
       "  example: track circle 3.5 0.5\n"
       "  example: track line 4 0.3 pid\n",
       &Console::cmdTrack},
      {"goto", "goto <x_m> <y_m> [speed_m_s]", "navigate to a point, going round obstacles",
       "  The robot's navigation automaton (go-to-goal, avoid, boundary following) drives to (x, y)\n"
       "  in its odometry frame (origin and x axis = its pose when robot_client started) at up to\n"
       "  speed_m_s (default: the robot's, 0.5 m/s; at most 1). People slow it down (Eq 9).\n"
       "  Waits for the Ack; the robot acks again (COMPLETED) within 0.1 m of the goal and goes IDLE,\n"
       "  and the console prints 'robot1: goto completed'. stop, estop or teleop end it.\n"
       "  Telemetry: expect nav_mode, goal_dist, goal_index, goal_count, nav_switches.\n"
       "  example: goto 2 0\n"
       "  example: goto 3.5 -1 0.3\n",
       &Console::cmdGoto},
      {"route", "route <file|name>", "navigate through the waypoints of a route file, or play its wheel test",
       "  The file is YAML (example: config/routes/warehouse_tour.yaml):\n"
       "    name: tour                          # optional, default: the file name\n"
       "    speed_m_s: 0.4                      # optional, default: the robot's (0.5 m/s)\n"
       "    waypoints_m: [x0, y0, x1, y1, ...]  # odometry frame, 1 to 100 points\n"
       "  A bad file is an error naming the file and the key. Acked like goto; COMPLETED after the\n"
       "  last point ('robot1: route completed'); goal_index counts the points reached.\n"
       "  A name without '/' is looked up as config/routes/<name>.yaml.\n"
       "  A route with `wheel_test:` instead of points plays open-loop wheel steps and chirps for\n"
       "  plant identification (mode WHEEL_TEST; recorded as a run; then `identify <run>`).\n"
       "  example: route config/routes/warehouse_tour.yaml\n"
       "  example: route identification\n",
       &Console::cmdRoute},
      {"inspect", "inspect <route> [speed_m_s]", "run a gas inspection route as a recorded run",
       "  <route> is a file or a name in config/routes/ (config/routes/<name>.yaml). The route's\n"
       "  points may carry dwell_s (the robot stops there), a camera preset (ptz: {pan_deg,\n"
       "  tilt_deg} or {home: true}) and a label; `map` names the site's world file, which the\n"
       "  run's report draws the concentration maps on. The robot navigates with the behaviour\n"
       "  strategy (people get right of way, Eq 9) and reacts to a gas HIGH alarm as configured\n"
       "  (client.yaml safety.gas_reaction: continue, stop = hold until resume, retreat). The run\n"
       "  is recorded (named 'inspection <name>') and ends with the route. Then: report <run-id>.\n"
       "  example: inspect gas_lab_inspection\n",
       &Console::cmdInspect},
      {"alarms", "alarms [all]", "gas alarms and gas sensor faults: active and unacknowledged ones, or all",
       "  One line per alarm: #number, robot, gas, level (LOW = A1, HIGH = A2, SENSOR_FAULT with\n"
       "  stuck, out_of_range or no_data), the reading and threshold, the worst reading, where the\n"
       "  robot was, how long ago it was raised, whether it is still active and acknowledged.\n"
       "  The robot raises and clears alarms (thresholds with hysteresis, minimum duration); the\n"
       "  operator acknowledges them with ack. Raised alarms print at once, in red with a bell on a\n"
       "  terminal, and the status line shows '| ALARM ...' while they are active.\n",
       &Console::cmdAlarms},
      {"ack", "ack <number>|all", "acknowledge a gas alarm (alarms lists the numbers)",
       "  Acknowledging does not clear an alarm (the robot does, when the gas is gone); it records\n"
       "  that the operator has seen it (catalog and run).\n"
       "  example: ack 3\n",
       &Console::cmdAck},
      {"identify", "identify <run-id>|last", "fit the hub-motor model to a recorded run (for tune)",
       "  Fits each wheel's gain, time constant, dead time and saturation to the commanded and\n"
       "  measured wheel speeds of the run's telemetry (an output-error fit), prints the model and\n"
       "  its fit (100 % = perfect), saves <run>/plant.yaml and makes it the plant tune uses.\n"
       "  'last' = the newest identification run. Record one with `route identification`.\n"
       "  example: identify last\n",
       &Console::cmdIdentify},
      {"tune", "tune [key=value ...] | tune list", "optimise the fuzzy-PID gains in simulation (NLopt), compare, save a session",
       "  Closed-loop simulations of the robot's own tracker on the plant (nominal, or the last\n"
       "  `identify`), each candidate over plant variations x noise seeds; cost = weighted max/RMS\n"
       "  position and angle error, convergence time, effort and saturation (docs/tuning.md).\n"
       "  Options: ref=circle|line|waypoints radius=3.5 speed=0.5 laps=1 length=10\n"
       "           params=kp,ki,kd,ke,kec,k1,k2,k3 (or all, adds a1,a2,a3) evals=1000\n"
       "           plant=current|nominal|<run-id>|<plant.yaml> variations=4 seeds=2 threads=0 seed=1\n"
       "           start=working|paper|tuned\n"
       "  Shows a progress bar and the best cost; Ctrl-C stops and keeps the best so far. Then\n"
       "  prints PID vs fuzzy-PID (paper gains) vs tuned, writes plots and summary.md into\n"
       "  runs/tuning/<session>/, books the session in the catalog and makes the tuned set the\n"
       "  working set (gains push sends it). `tune list`: the sessions in the catalog.\n"
       "  example: tune evals=300 speed=0.5\n",
       &Console::cmdTune},
      {"gains", "gains show [robot] | gains set <name>=<value>...|paper|tuned|robot | gains push [robot] | "
                "gains revert [robot] | gains export <file.yaml> | gains import <file.yaml>",
       "the tracking gains: working set, push to a robot, revert, files",
       "  show: working set, the robot's set in force (with its version), the paper's, the tuned.\n"
       "  set: edit the working set (kp ki kd ke kec k1 k2 k3 a1 a2 a3; bounds are checked).\n"
       "  push: send the working set; the robot checks it, applies it at its next control tick\n"
       "    (also to a path being tracked) and answers with the version now in force, or why not.\n"
       "  revert: push the set the robot had in force before its current one.\n"
       "  export/import: a YAML file of the gains plus the .fis fuzzy system beside it; an\n"
       "    imported .fis that differs from the loaded one is pushed with the gains.\n"
       "  example: gains set kp=12 ki=3\n  example: gains push\n",
       &Console::cmdGains},
      {"control", "control [take [force] | release]", "who controls each robot; take or release the selected robot",
       "  One session (console) at a time controls a robot: only its motion commands (drive, teleop,\n"
       "  track, goto, route, inspect, resume, ptz, gains push) reach the robot; the first such command\n"
       "  takes a free robot. Other sessions observe: status, events and runs; stop and estop always work.\n"
       "  control               this session's name and every robot's controlling session\n"
       "  control take          take the selected robot (refused while another session holds it)\n"
       "  control take force    take it over from another session: the robot is stopped first and\n"
       "                        the other session is told\n"
       "  control release       let go of the selected robot (its teleop set-point is cleared)\n",
       &Console::cmdControl},
      {"stop", "stop", "zero the set-point and stop re-sending (not latched)",
       "  Prints the robot's answer: 'robot1: stop accepted', '... rejected: <reason>' or\n"
       "  'robot1: no ack within 1 s' (the last two are errors).\n",
       &Console::cmdStop},
      {"estop", "estop", "emergency stop, latched until resume",
       "  Clears the set-point and sends EStop; waits up to 1 s for the Ack.\n", &Console::cmdEstop},
      {"resume", "resume", "clear a latched e-stop or failsafe",
       "  Waits up to 1 s for the Ack; e.g. 'robot1: resume rejected: <reason>'.\n", &Console::cmdResume},
      {"video", "video on|off|keyframe|stats | video res <W>x<H> | video fps <n> | video bitrate <kbit/s>",
       "control the selected robot's camera stream; show its figures",
       "  on/off start and stop streaming; keyframe asks for an IDR now (the server also asks by\n"
       "  itself, at most every 0.3 s, when it lost part of a picture).\n"
       "  res: even width and height, 64 to 4096 (e.g. 1280x720); fps: 1 to 120; bitrate: 50 to\n"
       "  50000 kbit/s. A new size or bitrate restarts the robot's encoder with an IDR.\n"
       "  stats: received/decoded fps, kbit/s, packet loss, glass-to-glass latency (mean, p50, p99),\n"
       "  counters, the SDP file for players, and the robot's encoder figures.\n"
       "  Play the stream elsewhere: ffplay -protocol_whitelist file,udp,rtp -fflags nobuffer\n"
       "    -flags low_delay video/robot1.sdp   (the server forwards the RTP to the SDP's port)\n"
       "  example: video res 1280x720\n",
       &Console::cmdVideo},
      {"ptz", "ptz <pan_deg> <tilt_deg> | ptz home", "point the camera mount (sent to the MCU)",
       "  pan counter-clockwise positive, [-180, 180] degrees; tilt up positive, [-90, 90].\n"
       "  example: ptz 30 -10\n",
       &Console::cmdPtz},
      {"snapshot", "snapshot [file.png]", "save the selected robot's latest decoded picture as PNG",
       "  Default file: <video.dir>/<robot>_<n>.png. Without a display the server also keeps\n"
       "  <video.dir>/<robot>_latest.png fresh (video.snapshot_period_s).\n",
       &Console::cmdSnapshot},
      {"record", "record start [name] | record stop", "record a run of the selected robot",
       "  A run is written to <recording.dir>/<run-id>/: run.mcap (telemetry, commands, acks, events,\n"
       "  camera frames; Foxglove opens it) and video.mp4, and listed in catalog.sqlite with its\n"
       "  summary. track, goto and route start one by themselves (recording.auto_start) and end it\n"
       "  when they complete or fail; record stop ends it ('stopped'). The status line shows REC.\n"
       "  example: record start night round B\n",
       &Console::cmdRecord},
      {"runs", "runs [robot|outcome|text] [limit]", "list recorded runs, newest first",
       "  A filter word is a robot id, an outcome (completed, stopped, failed, incomplete,\n"
       "  running) or text in the run's name. Default limit 20.\n"
       "  example: runs robot1\n",
       &Console::cmdRuns},
      {"run", "run show <run-id>", "a recorded run's summary, files and counts",
       "  example: run show 20261122-083015-robot1\n", &Console::cmdRun},
      {"report", "report <run-id>", "write a run's report: PNG plots and summary.md in <run>/report/",
       "  Plots: trajectory (with the tracking reference), speed and nearest person with the proxemic\n"
       "  zones, tracking errors, gas concentrations; summary.md links them and the run's files.\n"
       "  example: report 20261122-083015-robot1\n",
       &Console::cmdReport},
      {"export", "export <run-id> csv [dir]", "one CSV per channel of a run's MCAP file (default <run>/csv/)",
       "  Columns: log_time_s, publish_time_s, then every field, nested ones dotted (pose.x_m).\n",
       &Console::cmdExport},
      {"replay", "replay <run-id> [speed]", "play a run's telemetry back as status lines (speed 0.1-100, default 1)",
       "  One status line per second of run time, and the run's events as they came.\n"
       "  example: replay 1 10\n",
       &Console::cmdReplay},
      {"wait", "wait <seconds>", "pause the console (events still print)",
       "  example: wait 2.5\n", &Console::cmdWait},
      {"expect", "expect <field> <op> <value> [<tol>] [within <seconds>]", "check a value (scripts, tests)",
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
       "  examples: expect robots >= 1 within 5\n"
       "            expect x ~ 2.0 0.05 within 10\n"
       "            expect mode == ESTOP within 1\n"
       "            expect nav_mode == FOLLOW_CW within 20\n",
       &Console::cmdExpect},
      {"echo", "echo <text>", "print text (to label script output)", "  example: echo --- leg 2 ---\n",
       &Console::cmdEcho},
      {"quit", "quit", "leave the console and shut the server down ('exit' too)", "", &Console::cmdQuit},
      {"exit", "exit", "same as quit", "", &Console::cmdQuit},
  };
  return kCommands;
}

const Console::CommandDef* Console::findCommand(const std::string& name) {
  for (const auto& c : commands())
    if (name == c.name) return &c;
  return nullptr;
}

std::string Console::helpText(const std::string& command) {
  if (command.empty()) {
    std::string s = "commands:\n";
    for (const auto& c : commands()) {
      if (std::string(c.name) == "exit") continue;
      const std::string syntax = c.syntax;
      s += syntax.size() <= 30 ? "  " + padRight(syntax, 30) + " " + c.summary + "\n"
                               : "  " + syntax + "\n  " + std::string(31, ' ') + c.summary + "\n";
    }
    s += "'help <command>' explains one; '#' starts a comment; 'try <command>' runs a command\n"
         "whose failure (e.g. an expected rejection) should not fail a script.\n";
    return s;
  }
  const CommandDef* c = findCommand(command);
  if (!c) return "";
  return std::string(c->syntax) + "\n  " + c->summary + "\n" + c->details;
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
  const std::string rest = at == std::string::npos ? "" : trim(line.substr(at));
  const Args args(words.begin() + 1, words.end());
  const bool ok = (this->*(c->run))(args, rest, line_no);
  out_.flush();
  return ok;
}

std::string Console::background() {
  sink_.consoleAlive();
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
  if (!control_) return true;
  const auto d = control_->authorizeMotion(robot, session_, clock_->nowNs());
  if (d.taken_now) out_ << robot << ": control taken by " << control_->sessionName(session_) << "\n";
  if (d.allowed) return true;
  out_ << robot << ": " << cmd << " refused: " << d.reason << "\n";
  ++tally_.errors;
  return false;
}

bool Console::cmdControl(const Args& args, const std::string&, int) {
  if (!control_) return fail("control", "this console has no sessions (no control arbiter)");
  if (args.empty()) {
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
  const bool take = args[0] == "take", release = args[0] == "release";
  const bool force = take && args.size() == 2 && args[1] == "force";
  if ((!take && !release) || (release && args.size() != 1) || (take && args.size() > 1 && !force))
    return fail("control", "syntax: control | control take [force] | control release");
  if (selected_.empty()) return fail("control", "no robot selected");
  const std::string robot = selected_;
  if (release) {
    std::string why;
    if (!control_->release(robot, session_, &why)) return fail("control", why);
    sink_.clearTeleop(robot);
    out_ << robot << ": control released; the robot is free\n";
    return true;
  }
  const auto r = control_->take(robot, session_, force, clock_->nowNs());
  if (!r.ok) return fail("control", r.reason);
  if (r.previous) {
    // The new operator starts from standstill: nothing of the old one's commands goes on.
    sink_.clearTeleop(robot);
    v1::Command stop;
    stop.mutable_stop();
    sink_.sendCommand(robot, std::move(stop));
    out_ << robot << ": control taken over from " << r.previous->name << " (robot stopped)\n";
  } else {
    out_ << robot << ": controlled by " << control_->sessionName(session_) << "\n";
  }
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

std::optional<v1::Ack> Console::waitAck(const std::string& robot_id, uint64_t command_id) {
  const int64_t deadline = deadlineAfter(options_.ack_timeout_s);
  for (;;) {
    if (auto a = registry_.ack(robot_id, command_id)) return a;
    if (clock_->nowNs() >= deadline) return std::nullopt;
    pump();
    // Acks come back within a millisecond or two on a working link; polling
    // finely keeps 'drive' + 'wait T' close to T of motion.
    if (!clock_->sleep(options_.ack_poll_period_s)) return std::nullopt;
  }
}

bool Console::cmdHelp(const Args& args, const std::string&, int) {
  if (args.size() > 1) return fail("help", "takes at most one command name");
  if (args.empty()) {
    out_ << helpText();
    return true;
  }
  const std::string text = helpText(args[0]);
  if (text.empty()) return fail("help", "unknown command '" + args[0] + "'");
  out_ << text;
  return true;
}

bool Console::cmdRobots(const Args& args, const std::string&, int) {
  if (!args.empty()) return fail("robots", "takes no arguments");
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

bool Console::cmdSelect(const Args& args, const std::string&, int) {
  if (args.size() != 1) return fail("select", "needs one robot id: select <robot>");
  if (!net::validRobotId(args[0])) return fail("select", "'" + args[0] + "' is not a valid robot id ([A-Za-z0-9_-]{1,64})");
  selected_ = args[0];
  const auto snap = registry_.snapshot(selected_, clock_->nowNs());
  out_ << "selected " << selected_ << (snap && snap->connected ? "" : " (not connected yet)") << "\n";
  return true;
}

bool Console::cmdStatus(const Args& args, const std::string&, int) {
  if (args.size() > 1) return fail("status", "takes at most one robot id");
  const std::string robot = args.empty() ? selected_ : args[0];
  if (robot.empty()) return fail("status", "no robot selected");
  out_ << statusText(robot) << "\n";
  return true;
}

bool Console::cmdDrive(const Args& args, const std::string&, int) {
  if (args.size() != 2) return fail("drive", "needs two numbers: drive <v_m_s> <w_rad_s>");
  const auto v = parseNumber(args[0]);
  if (!v) return fail("drive", "'" + args[0] + "' is not a number");
  const auto w = parseNumber(args[1]);
  if (!w) return fail("drive", "'" + args[1] + "' is not a number");
  if (std::fabs(*v) > options_.max_v_m_s)
    return fail("drive", "v " + args[0] + " m/s is outside [-" + fmtShort(options_.max_v_m_s) + ", " +
                             fmtShort(options_.max_v_m_s) + "]");
  if (std::fabs(*w) > options_.max_w_rad_s)
    return fail("drive", "w " + args[1] + " rad/s is outside [-" + fmtShort(options_.max_w_rad_s) + ", " +
                             fmtShort(options_.max_w_rad_s) + "]");
  const auto robot = connectedRobot("drive");
  if (!robot || !mayMove(*robot, "drive")) return false;
  const uint64_t id = sink_.setTeleop(*robot, *v, *w);
  if (id == 0) return fail("drive", *robot + " is not connected");
  const std::string what = "drive " + fmtSigned(*v) + " m/s " + fmtSigned(*w) + " rad/s";
  const auto ack = waitAck(*robot, id);
  if (!ack) {
    sink_.clearTeleop(*robot);
    out_ << *robot << ": " << what << ": no ack within " << fmtShort(options_.ack_timeout_s) << " s (set-point cleared)\n";
    ++tally_.errors;
    return false;
  }
  if (ack->status() == v1::Ack::REJECTED) {
    sink_.clearTeleop(*robot);
    out_ << *robot << ": " << what << " rejected: " << ack->reason() << "\n";
    ++tally_.errors;
    return false;
  }
  out_ << *robot << ": " << what << " accepted (re-sent until stop)\n";
  return true;
}

bool Console::cmdTeleop(const Args& args, const std::string&, int) {
  if (args.size() > 1) return fail("teleop", "takes at most one mode: teleop [step|hold]");
  KeyboardTeleop::Mode mode = KeyboardTeleop::Mode::kStep;
  if (!args.empty() && !parseTeleopMode(args[0], mode))
    return fail("teleop", "unknown mode '" + args[0] + "' (step or hold)");
  if (!teleop_handler_) return fail("teleop", "keyboard teleop needs an interactive terminal (scripts use drive)");
  const auto robot = connectedRobot("teleop");
  if (!robot || !mayMove(*robot, "teleop")) return false;
  if (!teleop_handler_(mode, *robot)) {
    ++tally_.errors;
    return false;
  }
  return true;
}

bool Console::cmdVideo(const Args& args, const std::string&, int) {
  static const char* kSyntax =
      "syntax: video on|off|keyframe|stats | video res <W>x<H> | video fps <n> | video bitrate <kbit/s>";
  if (args.empty() || args.size() > 2) return fail("video", kSyntax);
  const std::string& what = args[0];
  if (what == "stats") {
    if (args.size() != 1) return fail("video", kSyntax);
    const auto robot = connectedRobot("video");
    if (!robot) return false;
    out_ << videoReport(*robot, registry_.snapshot(*robot, clock_->nowNs()), video_);
    return true;
  }
  v1::Command c;
  auto* v = c.mutable_video();
  if ((what == "on" || what == "off" || what == "keyframe") && args.size() == 1) {
    if (what == "keyframe") v->set_keyframe(true);
    else v->set_enabled(what == "on");
    return sendAndReport("video " + what, std::move(c));
  }
  if (what != "res" && what != "fps" && what != "bitrate" && what != "on" && what != "off" && what != "keyframe")
    return fail("video", "unknown '" + what + "'; " + kSyntax);
  if (args.size() != 2) return fail("video", kSyntax);
  if (what == "res") {
    const auto x = args[1].find('x');
    const auto w = x == std::string::npos ? std::nullopt : parseInteger(args[1].substr(0, x));
    const auto h = x == std::string::npos ? std::nullopt : parseInteger(args[1].substr(x + 1));
    if (!w || !h || *w < 64 || *h < 64 || *w > 4096 || *h > 4096 || *w % 2 || *h % 2)
      return fail("video", "res '" + args[1] + "': want <W>x<H>, even, 64 to 4096 (e.g. 1280x720)");
    v->set_width(static_cast<uint32_t>(*w));
    v->set_height(static_cast<uint32_t>(*h));
  } else if (what == "fps") {
    const auto f = parseNumber(args[1]);
    if (!f || !(*f >= 1 && *f <= 120)) return fail("video", "fps '" + args[1] + "': want 1 to 120");
    v->set_fps(*f);
  } else if (what == "bitrate") {
    const auto b = parseInteger(args[1]);
    if (!b || *b < 50 || *b > 50000) return fail("video", "bitrate '" + args[1] + "': want 50 to 50000 kbit/s");
    v->set_bitrate_kbps(static_cast<uint32_t>(*b));
  } else {
    return fail("video", "unknown '" + what + "'; " + kSyntax);
  }
  return sendAndReport("video " + what, std::move(c));
}

bool Console::cmdPtz(const Args& args, const std::string&, int) {
  v1::Command c;
  auto* p = c.mutable_ptz();
  if (args.size() == 1 && args[0] == "home") {
    p->set_home(true);
    return sendAndReport("ptz", std::move(c));
  }
  const auto pan = args.size() == 2 ? parseNumber(args[0]) : std::nullopt;
  const auto tilt = args.size() == 2 ? parseNumber(args[1]) : std::nullopt;
  if (!pan || !tilt) return fail("ptz", "syntax: ptz <pan_deg> <tilt_deg> | ptz home");
  if (std::abs(*pan) > 180 || std::abs(*tilt) > 90)
    return fail("ptz", "pan must be within [-180, 180] and tilt within [-90, 90] degrees");
  p->set_pan_rad(*pan * M_PI / 180.0);
  p->set_tilt_rad(*tilt * M_PI / 180.0);
  return sendAndReport("ptz", std::move(c));
}

bool Console::cmdSnapshot(const Args& args, const std::string&, int) {
  if (args.size() > 1) return fail("snapshot", "syntax: snapshot [file.png]");
  if (!video_) return fail("snapshot", "the server runs without video (video.enabled: false or --no-video)");
  if (selected_.empty()) return fail("snapshot", "no robot selected");
  try {
    const std::string path = video_->snapshot(selected_, args.empty() ? "" : args[0]);
    out_ << selected_ << ": snapshot " << path << "\n";
    return true;
  } catch (const std::exception& e) {
    return fail("snapshot", e.what());
  }
}

std::string Console::statusText(const std::string& robot) const {
  std::string s = statusLine(robot, registry_.snapshot(robot, clock_->nowNs()), video_);
  if (recorder_)
    if (const auto run = recorder_->activeRun(robot)) s += " | REC " + *run;
  return s;
}

bool Console::cmdRecord(const Args& args, const std::string& rest, int) {
  if (!recorder_) return fail("record", "the server records nothing (recording.enabled: false or --no-record)");
  if (args.empty() || (args[0] != "start" && args[0] != "stop") || (args[0] == "stop" && args.size() > 1))
    return fail("record", "syntax: record start [name] | record stop");
  if (selected_.empty()) return fail("record", "no robot selected");
  if (args[0] == "stop") {
    const auto id = recorder_->stop(selected_, "stopped");
    if (!id) return fail("record", selected_ + " is not recording");
    out_ << selected_ << ": run " << *id << " stopped\n";
    return true;
  }
  const auto sp = rest.find("start");
  std::string name = sp == std::string::npos ? "" : rest.substr(sp + 5);
  name.erase(0, name.find_first_not_of(" \t"));
  try {
    const std::string id = recorder_->start(selected_, name);
    out_ << selected_ << ": recording run " << id << "\n";
    return true;
  } catch (const std::exception& e) {
    return fail("record", e.what());
  }
}

bool Console::cmdRuns(const Args& args, const std::string&, int) {
  if (!recorder_) return fail("runs", "the server records nothing (recording.enabled: false or --no-record)");
  catalog::RunFilter f;
  f.limit = 20;
  for (const auto& a : args) {
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
  const auto runs = recorder_->catalog().listRuns(f);
  out_ << padRight("run", 28) << padRight("robot", 10) << padRight("started (UTC)", 26) << padRight("outcome", 12)
       << "name\n";
  for (const auto& r : runs)
    out_ << padRight(r.id, 28) << padRight(r.robot, 10) << padRight(catalog::formatIsoUtc(r.start), 26)
         << padRight(r.outcome.empty() ? "running" : r.outcome, 12) << r.name << "\n";
  out_ << runs.size() << " run" << (runs.size() == 1 ? "" : "s") << "\n";
  return true;
}

bool Console::cmdRun(const Args& args, const std::string&, int) {
  if (!recorder_) return fail("run", "the server records nothing (recording.enabled: false or --no-record)");
  if (args.size() != 2 || args[0] != "show") return fail("run", "syntax: run show <run-id>");
  const auto d = recorder_->catalog().run(args[1]);
  if (!d) return fail("run", "no run '" + args[1] + "' in the catalog (see runs)");
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

bool Console::simpleCommand(const std::string& name, const Args& args, v1::Command cmd) {
  if (!args.empty()) return fail(name, "takes no arguments");
  return sendAndReport(name, std::move(cmd));
}

bool Console::cmdTrack(const Args& args, const std::string&, int) {
  static const char* kSyntax =
      "syntax: track circle <radius_m> [speed_m_s] [laps] [controller] | track line <length_m> [speed_m_s] [controller]";
  if (args.size() < 2) return fail("track", kSyntax);
  std::vector<double> nums;
  std::string controller;
  for (std::size_t i = 1; i < args.size(); ++i) {
    if (const auto v = parseNumber(args[i]); v && controller.empty()) {
      nums.push_back(*v);
    } else if (controller.empty() && (args[i] == "fuzzy_pid" || args[i] == "pid" || args[i] == "direct")) {
      controller = args[i];
    } else {
      return fail("track", "'" + args[i] + "' is neither a number nor a controller (fuzzy_pid, pid, direct)");
    }
  }
  v1::Command c;
  auto* t = c.mutable_track();
  t->set_controller(controller);
  const double speed = nums.size() > 1 ? nums[1] : 0.5;
  if (!(speed > 0) || speed > 1.0) return fail("track", "speed " + fmtShort(speed) + " m/s is outside (0, 1]");
  if (args[0] == "circle") {
    if (nums.empty() || nums.size() > 3) return fail("track", kSyntax);
    if (std::abs(nums[0]) < 0.1 || std::abs(nums[0]) > 100) return fail("track", "radius must be 0.1 to 100 m (negative turns right)");
    const double laps = nums.size() > 2 ? nums[2] : 1.0;
    if (!(laps > 0) || laps > 100) return fail("track", "laps must be in (0, 100]");
    t->mutable_circle()->set_radius_m(nums[0]);
    t->mutable_circle()->set_speed_m_s(speed);
    t->mutable_circle()->set_laps(laps);
  } else if (args[0] == "line") {
    if (nums.empty() || nums.size() > 2) return fail("track", kSyntax);
    if (!(nums[0] > 0) || nums[0] > 1000) return fail("track", "length must be in (0, 1000] m");
    t->mutable_line()->set_length_m(nums[0]);
    t->mutable_line()->set_speed_m_s(speed);
  } else {
    return fail("track", "unknown path '" + args[0] + "' (circle or line)");
  }
  return sendAndReport("track", std::move(c), true);
}

bool Console::cmdGoto(const Args& args, const std::string&, int) {
  if (args.size() < 2 || args.size() > 3) return fail("goto", "needs two or three numbers: goto <x_m> <y_m> [speed_m_s]");
  std::vector<double> nums;
  for (const auto& a : args) {
    const auto v = parseNumber(a);
    if (!v) return fail("goto", "'" + a + "' is not a number");
    nums.push_back(*v);
  }
  if (std::fabs(nums[0]) > 1000 || std::fabs(nums[1]) > 1000) return fail("goto", "x and y must be in [-1000, 1000] m");
  if (nums.size() > 2 && (!(nums[2] > 0) || nums[2] > kMaxRouteSpeed_m_s))
    return fail("goto", "speed " + args[2] + " m/s is outside (0, " + fmtShort(kMaxRouteSpeed_m_s) + "]");
  v1::Command c;
  auto* g = c.mutable_go_to();
  auto* p = g->add_points();
  p->set_x_m(nums[0]);
  p->set_y_m(nums[1]);
  if (nums.size() > 2) g->set_speed_m_s(nums[2]);
  return sendAndReport("goto", std::move(c), true);
}

bool Console::cmdRoute(const Args& args, const std::string&, int) {
  if (args.size() != 1) return fail("route", "needs one route: route <file|name>");
  Route r;
  try {
    // A path is read as given (its own errors); a bare name is looked up in config/routes/.
    const bool path = args[0].find('/') != std::string::npos || args[0].ends_with(".yaml");
    r = loadRouteFile(path ? args[0] : resolveRoute(args[0]));
  } catch (const config::ConfigError& e) {
    return fail("route", e.what());
  }
  v1::Command c;
  if (r.isWheelTest()) {
    *c.mutable_wheel_test() = wheelTestOf(r);
    double total = 0.0;
    for (const auto& g : r.wheel_test) total += g.duration_s;
    out_ << "wheel test '" << r.name << "': " << r.wheel_test.size() << " segments, " << fmtShort(total, 1)
         << " s of open-loop steps and chirps (identify <run> fits the plant afterwards)\n";
    return sendAndReport("route", std::move(c), true);
  }
  *c.mutable_go_to() = goToOf(r);
  out_ << "route '" << r.name << "': " << r.points.size() << " points"
       << (r.speed_m_s > 0 ? " at " + fmtShort(r.speed_m_s) + " m/s" : std::string()) << "\n";
  return sendAndReport("route", std::move(c), true);
}

bool Console::sendAndReport(const std::string& name, v1::Command cmd, bool runs) {
  const auto robot = connectedRobot(name);
  if (!robot) return false;
  // Everything but stop, e-stop and the camera stream's settings moves the robot or its mount.
  const bool motion = !cmd.has_stop() && !cmd.has_estop() && !cmd.has_video();
  if (motion && !mayMove(*robot, name)) return false;
  const uint64_t id = sink_.sendCommand(*robot, std::move(cmd));
  if (id == 0) return fail(name, *robot + " is not connected");
  const auto ack = waitAck(*robot, id);
  if (!ack) {
    out_ << *robot << ": " << name << ": no ack within " << fmtShort(options_.ack_timeout_s) << " s\n";
    ++tally_.errors;
    return false;
  }
  switch (ack->status()) {
    case v1::Ack::ACCEPTED:
      out_ << *robot << ": " << name << " accepted\n";
      if (runs) {
        // One run per robot: a new one ends the previous (the robot does the same).
        std::erase_if(runs_, [&](const Run& r) { return r.robot_id == *robot; });
        runs_.push_back({*robot, id, name});
      }
      return true;
    case v1::Ack::COMPLETED: out_ << *robot << ": " << name << " completed\n"; return true;
    case v1::Ack::FAILED:
      out_ << *robot << ": " << name << " failed: " << ack->reason() << "\n";
      ++tally_.errors;
      return false;
    case v1::Ack::REJECTED:
      out_ << *robot << ": " << name << " rejected: " << ack->reason() << "\n";
      ++tally_.errors;
      return false;
    default:
      out_ << *robot << ": " << name << ": ack with an unknown status " << ack->status() << "\n";
      ++tally_.errors;
      return false;
  }
}

bool Console::cmdStop(const Args& args, const std::string&, int) {
  v1::Command c;
  c.mutable_stop();
  return simpleCommand("stop", args, c);
}

bool Console::cmdEstop(const Args& args, const std::string&, int) {
  v1::Command c;
  c.mutable_estop();
  return simpleCommand("estop", args, c);
}

bool Console::cmdResume(const Args& args, const std::string&, int) {
  v1::Command c;
  c.mutable_resume();
  return simpleCommand("resume", args, c);
}

bool Console::cmdWait(const Args& args, const std::string&, int) {
  if (args.size() != 1) return fail("wait", "needs one number of seconds: wait <seconds>");
  const auto s = parseNumber(args[0]);
  if (!s) return fail("wait", "'" + args[0] + "' is not a number");
  if (*s < 0 || *s > 3600) return fail("wait", args[0] + " s is outside [0, 3600]");
  if (!sleepPumping(*s)) return fail("wait", "interrupted (server stopping)");
  return true;
}

bool Console::cmdExpect(const Args& args, const std::string&, int line_no) {
  const auto parsed = parseExpect(args);
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
    if (r.ok && compare(spec.op, r.value, spec.value, spec.tol)) {
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

bool Console::cmdEcho(const Args&, const std::string& rest, int) {
  out_ << rest << "\n";
  return true;
}

bool Console::cmdQuit(const Args& args, const std::string&, int) {
  if (!args.empty()) return fail("quit", "takes no arguments");
  quit_ = true;
  return true;
}

}  // namespace inspect::server
