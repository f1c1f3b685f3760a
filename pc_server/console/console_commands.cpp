// The console's command table: every command, its arguments and its help
// text (docs/console.md), and the help built from it.
#include "pc_server/console/console.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "pc_server/operator/command_limits.hpp"
#include "pc_server/operator/route_file.hpp"
#include "pc_server/console/text_util.hpp"
#include "pc_server/recording/recorder.hpp"
#include "pc_server/video/video_hub.hpp"
#include "shared/config/config_node.hpp"
#include "shared/util/clock.hpp"

namespace inspect::server {

using namespace args;
using Source = ArgSpec::Source;

namespace {
/// track's last argument: the tracking controller (default: the robot's config).
ArgSpec controller() {
  ArgSpec a = choice("controller", {"fuzzy_pid", "pid", "direct"}, "controller");
  a.shown = "<controller>";
  return a;
}
/// A command that takes no arguments: one empty form.
std::vector<CommandForm> noArguments() { return {CommandForm{}}; }
}  // namespace

// Commands of the session: help, robots, selection, status, control.
std::vector<Console::CommandDef> Console::sessionCommands() {
  return {
    {"help", {{opt(completing(word("command", "command name"), Source::kCommands))}}, "list the commands, or explain one",
     "  help          lists every command\n"
     "  help drive    explains one command\n",
     &Console::cmdHelp},
    {"robots", {{keyword("--fleet")}, {}}, "table of robots: id, connected, address, telemetry Hz, mode, telemetry age",
     "  Lists every robot that connected since the server started; '*' marks the selected one.\n"
     "  --fleet: with a catalog several servers share, every server's robots: online or not\n"
     "  (unknown when its server has not been seen for 10 s), mode, where, and which server\n"
     "  holds the link and where to attach to it (commands go to that server).\n"
     "  example: robots --fleet\n",
     &Console::cmdRobots},
    {"select", {{completing(word("robot", "robot id"), Source::kRobots)}}, "choose the robot that drive/stop/estop/resume/status/expect act on",
     "  The robot need not be connected yet. With no selection, the first robot to connect\n"
     "  is selected automatically.\n"
     "  example: select robot2\n",
     &Console::cmdSelect},
    {"status", {{opt(completing(word("robot", "robot id"), Source::kRobots))}}, "one status line of the selected (or named) robot",
     "  example: status\n"
     "  robot1 | TELEOP | v +0.30 w +0.00 | x 1.20 y 0.00 th +0.00 | us 1.23 2.01 -- 0.88 | faults none |"
     " tlm 50 Hz | serial ok\n",
     &Console::cmdStatus},
    {"control", {CommandForm{}, {subcommand("take"), opt(keyword("force"))}, {keyword("release")}}, "who controls each robot; take or release the selected robot",
     "  One session (console) at a time controls a robot: only its motion commands (drive, teleop,\n"
     "  track, goto, route, inspect, resume, ptz, gains push) reach the robot; the first such command\n"
     "  takes a free robot. Other sessions observe: status, events and runs; stop and estop always work.\n"
     "  control               this session's name and every robot's controlling session\n"
     "  control take          take the selected robot (refused while another session holds it)\n"
     "  control take force    take it over from another session: the robot is stopped first and\n"
     "                        the other session is told\n"
     "  control release       let go of the selected robot (its teleop set-point is cleared)\n",
     &Console::cmdControl},
  };
}

// Commands of moving the robot and its camera.
std::vector<Console::CommandDef> Console::motionCommands() {
  return {
    {"drive", {{number("v_m_s"), number("w_rad_s")}}, "set the teleop set-point; re-sent at teleop_resend_hz until stop",
     "  v in [-1, 1] m/s (forward positive), w in [-2, 2] rad/s (counter-clockwise positive).\n"
     "  The server re-sends the set-point (default 20 Hz) so the robot's 300 ms deadman stays\n"
     "  quiet while the console and link work; in an attached console (--attach) it lapses\n"
     "  0.3 s after the session's last line or keep-alive. Waits up to 1 s for the robot's Ack of the first\n"
     "  command; a rejection or no Ack clears the set-point and is an error.\n"
     "  example: drive 0.3 0      (straight ahead at 0.3 m/s)\n"
     "  example: drive 0 0.5      (turn on the spot, 0.5 rad/s to the left)\n",
     &Console::cmdDrive},
    {"teleop", {{opt(choice("mode", {"step", "hold"}, "mode"))}}, "keyboard teleop (interactive terminal only)",
     "  step (default): w/s or Up/Down step v by 0.05 m/s, a/d or Left/Right step w by 0.1 rad/s\n"
     "    (clamped to +-1.0 m/s, +-2.0 rad/s); the set-point stays until changed.\n"
     "  hold: hold w/s/a/d (or arrows) to drive at 0.3 m/s or 1.0 rad/s; releasing the key\n"
     "    zeroes the set-point (deadman: 300 ms before the first auto-repeat, 200 ms after).\n"
     "  Both: space (or x, 0) zeroes at once; q or Esc leaves teleop and sends stop.\n",
     &Console::cmdTeleop},
    {"track",
     {{subcommand("circle", "path"), number("radius_m"), opt(number("speed_m_s")), opt(number("laps")), opt(controller())},
      {keyword("line"), number("length_m"), opt(number("speed_m_s")), opt(controller())}},
     "track a reference path from the robot's current pose (Eqs 10-15)",
     "  circle: radius > 0 turns left (counter-clockwise), < 0 right; speed default 0.5 m/s, laps 1.\n"
     "  line: straight ahead. controller: fuzzy_pid, pid or direct (default: the robot's config).\n"
     "  Waits for the Ack; the robot acks again (COMPLETED) when the path is done and goes IDLE.\n"
     "  Telemetry then carries the reference pose and the errors (expect pos_err, max_pos_err, ...).\n"
     "  example: track circle 3.5 0.5\n"
     "  example: track line 4 0.3 pid\n",
     &Console::cmdTrack},
    {"goto", {{number("x_m"), number("y_m"), opt(number("speed_m_s")), opt(keyword("force"))}},
     "navigate to a point, going round obstacles",
     "  The robot's navigation automaton (go-to-goal, avoid, boundary following) drives to (x, y)\n"
     "  in its odometry frame (origin and x axis = its pose when robot_client started) at up to\n"
     "  speed_m_s (default: the robot's, 0.5 m/s; at most 1). People slow it down (Eq 9).\n"
     "  A goal outside the robot's site map (the box of its walls) is refused with the map's\n"
     "  bounds; `force` sends it anyway.\n"
     "  Waits for the Ack; the robot acks again (COMPLETED) within 0.1 m of the goal and goes IDLE,\n"
     "  and the console prints 'robot1: goto completed'. stop, estop or teleop end it.\n"
     "  Telemetry: expect nav_mode, goal_dist, goal_index, goal_count, nav_switches.\n"
     "  example: goto 2 0\n"
     "  example: goto 3.5 -1 0.3\n",
     &Console::cmdGoto},
    {"route", {{word("file|name", "route")}}, "navigate through the waypoints of a route file, or play its wheel test",
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
    {"stop", noArguments(), "zero the set-point and stop re-sending (not latched)",
     "  Prints the robot's answer: 'robot1: stop accepted', '... rejected: <reason>' or\n"
     "  'robot1: no ack within 1 s' (the last two are errors).\n",
     &Console::cmdStop},
    {"estop", noArguments(), "emergency stop, latched until resume",
     "  Clears the set-point and sends EStop; waits up to 1 s for the Ack.\n", &Console::cmdEstop},
    {"resume", noArguments(), "clear a latched e-stop or failsafe",
     "  Waits up to 1 s for the Ack; e.g. 'robot1: resume rejected: <reason>'.\n", &Console::cmdResume},
    {"video",
     {{choice("what", {"on", "off", "keyframe", "stats"})},
      {keyword("res"), wanting(size("size"), kVideoSizeWant)},
      {keyword("fps"), wanting(number("n"), kVideoFpsWant)},
      {keyword("bitrate"), wanting(integer("kbit/s"), kVideoBitrateWant)}},
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
    {"ptz", {{number("pan_deg"), number("tilt_deg")}, {keyword("home")}}, "point the camera mount (sent to the MCU)",
     "  pan counter-clockwise positive, [-180, 180] degrees; tilt up positive, [-90, 90].\n"
     "  example: ptz 30 -10\n",
     &Console::cmdPtz},
    {"snapshot", {{opt(word("file.png"))}}, "save the selected robot's latest decoded picture as PNG",
     "  Default file: <video.dir>/<robot>_<n>.png. Without a display the server also keeps\n"
     "  <video.dir>/<robot>_latest.png fresh (video.snapshot_period_s).\n",
     &Console::cmdSnapshot},
    {"foxglove", noArguments(), "the Foxglove bridge: clients, subscriptions, send queues, drops",
     "  One line per connected Foxglove/Lichtblick client (its operator session, how long it has\n"
     "  been connected, subscriptions, queued messages and bytes, messages sent, data and video\n"
     "  messages dropped for a slow reader, its messages refused), then the topics it subscribed\n"
     "  to and publishes on. docs/foxglove.md.\n",
     &Console::cmdFoxglove},
  };
}

// Commands of gas inspection and alarms (docs/gas.md).
std::vector<Console::CommandDef> Console::gasCommands() {
  return {
    {"inspect", {{word("route"), opt(number("speed_m_s"))}}, "run a gas inspection route as a recorded run",
     "  <route> is a file or a name in config/routes/ (config/routes/<name>.yaml). The route's\n"
     "  points may carry dwell_s (the robot stops there), a camera preset (ptz: {pan_deg,\n"
     "  tilt_deg} or {home: true}) and a label; `map` names the site's world file, which the\n"
     "  run's report draws the concentration maps on. The robot navigates with the behaviour\n"
     "  strategy (people get right of way, Eq 9) and reacts to a gas HIGH alarm as configured\n"
     "  (client.yaml safety.gas_reaction: continue, stop = hold until resume, retreat). The run\n"
     "  is recorded (named 'inspection <name>') and ends with the route. Then: report <run-id>.\n"
     "  example: inspect gas_lab_inspection\n",
     &Console::cmdInspect},
    {"alarms", {{opt(keyword("all"))}}, "gas alarms and gas sensor faults: active and unacknowledged ones, or all",
     "  One line per alarm: #number, robot, gas, level (LOW = A1, HIGH = A2, SENSOR_FAULT with\n"
     "  stuck, out_of_range or no_data), the reading and threshold, the worst reading, where the\n"
     "  robot was, how long ago it was raised, whether it is still active and acknowledged.\n"
     "  The robot raises and clears alarms (thresholds with hysteresis, minimum duration); the\n"
     "  operator acknowledges them with ack. Raised alarms print at once, in red with a bell on a\n"
     "  terminal, and the status line shows '| ALARM ...' while they are active.\n",
     &Console::cmdAlarms},
    {"ack", {{keyword("all")}, {word("number")}}, "acknowledge a gas alarm (alarms lists the numbers)",
     "  Acknowledging does not clear an alarm (the robot does, when the gas is gone); it records\n"
     "  that the operator has seen it (catalog and run).\n"
     "  example: ack 3\n",
     &Console::cmdAck},
  };
}

// Commands of the tuning host (docs/tuning.md).
std::vector<Console::CommandDef> Console::tuningCommands() {
  return {
    {"identify", {{word("run-id|last")}}, "fit the hub-motor model to a recorded run (for tune)",
     "  Fits each wheel's gain, time constant, dead time and saturation to the commanded and\n"
     "  measured wheel speeds of the run's telemetry (an output-error fit), prints the model and\n"
     "  its fit (100 % = perfect), saves <run>/plant.yaml and makes it the plant tune uses.\n"
     "  'last' = the newest identification run. Record one with `route identification`.\n"
     "  example: identify last\n",
     &Console::cmdIdentify},
    {"tune", {{subcommand("list")}, {opt(keyValues("options", "key=value ...", tuneOptionKeys()))}}, "optimise the fuzzy-PID gains in simulation (NLopt), compare, save a session",
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
    {"gains",
     {{subcommand("show"), opt(completing(word("robot"), Source::kRobots))},
      {keyword("set"), choice("preset", {"paper", "tuned", "robot"})},
      {keyword("set"), keyValues("gains", "<name>=<value>...")},
      {keyword("push"), opt(completing(word("robot"), Source::kRobots))},
      {keyword("revert"), opt(completing(word("robot"), Source::kRobots))},
      {keyword("export"), word("file.yaml")},
      {keyword("import"), word("file.yaml")}},
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
  };
}

// Commands of recorded runs (docs/recording.md).
std::vector<Console::CommandDef> Console::runCommands() {
  return {
    {"record", {{subcommand("start"), opt(rest("name"))}, {keyword("stop")}}, "record a run of the selected robot",
     "  A run is written to <recording.dir>/<run-id>/: run.mcap (telemetry, commands, acks, events,\n"
     "  camera frames; Foxglove opens it) and video.mp4, and listed in catalog.sqlite with its\n"
     "  summary. track, goto and route start one by themselves (recording.auto_start) and end it\n"
     "  when they complete or fail; record stop ends it ('stopped'). The status line shows REC.\n"
     "  example: record start night round B\n",
     &Console::cmdRecord},
    {"runs", {{keyword("--fleet"), words("[robot|outcome|text] [limit]")}, {words("[robot|outcome|text] [limit]")}},
     "list recorded runs, newest first",
     "  A filter word is a robot id, an outcome (completed, stopped, failed, incomplete,\n"
     "  running) or text in the run's name. Default limit 20.\n"
     "  With a catalog that several servers share (--catalog postgresql://...), the runs of\n"
     "  this server; --fleet: every server's, with the server and where to attach to it.\n"
     "  example: runs robot1\n"
     "  example: runs --fleet incomplete\n",
     &Console::cmdRuns},
    {"run", {{subcommand("show"), word("run-id")}}, "a recorded run's summary, files and counts",
     "  example: run show 20261122-083015-robot1\n", &Console::cmdRun},
    {"report", {{word("run-id")}}, "write a run's report: PNG plots and summary.md in <run>/report/",
     "  Plots: trajectory (with the tracking reference), speed and nearest person with the proxemic\n"
     "  zones, tracking errors, gas concentrations; summary.md links them and the run's files.\n"
     "  example: report 20261122-083015-robot1\n",
     &Console::cmdReport},
    {"export", {{word("run-id"), keyword("csv"), opt(word("dir"))}}, "one CSV per channel of a run's MCAP file (default <run>/csv/)",
     "  Columns: log_time_s, publish_time_s, then every field, nested ones dotted (pose.x_m).\n",
     &Console::cmdExport},
    {"replay", {{word("run-id"), opt(within(number("speed"), 0.1, 100))}}, "play a run's telemetry back as status lines (speed 0.1-100, default 1)",
     "  One status line per second of run time, and the run's events as they came.\n"
     "  example: replay 1 10\n",
     &Console::cmdReplay},
  };
}

// Commands of scripts: waits, checks, output, leaving.
std::vector<Console::CommandDef> Console::scriptCommands() {
  return {
    {"wait", {{within(number("seconds"), 0, 3600, "s")}}, "pause the console (events still print)",
     "  example: wait 2.5\n", &Console::cmdWait},
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
     &Console::cmdExpect},
    {"echo", {{opt(rest("text"))}}, "print text (to label script output)", "  example: echo --- leg 2 ---\n",
     &Console::cmdEcho},
    {"quit", noArguments(), "leave the console and shut the server down ('exit' too)", "", &Console::cmdQuit},
    {"exit", noArguments(), "same as quit", "", &Console::cmdQuit},
  };
}

const std::vector<Console::CommandDef>& Console::commands() {
  static const std::vector<CommandDef> kCommands = [] {
    std::vector<CommandDef> all;
    for (auto family : {sessionCommands, motionCommands, gasCommands, tuningCommands, runCommands, scriptCommands})
      for (auto& c : family()) all.push_back(c);
    return all;
  }();
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
      const std::string syntax = commandSyntax(c.name, c.forms);
      s += syntax.size() <= 30 ? "  " + padRight(syntax, 30) + " " + c.summary + "\n"
                               : "  " + syntax + "\n  " + std::string(31, ' ') + c.summary + "\n";
    }
    s += "'help <command>' explains one; '#' starts a comment; 'try <command>' runs a command\n"
         "whose failure (e.g. an expected rejection) should not fail a script.\n";
    return s;
  }
  const CommandDef* c = findCommand(command);
  if (!c) return "";
  // One line per form: "ptz <pan_deg> <tilt_deg>", then "ptz home".
  std::string s;
  for (const auto& f : formSyntaxes(c->name, c->forms)) s += f + "\n";
  return s + "  " + c->summary + "\n" + c->details;
}

std::string Console::tableProblems() {
  std::string out;
  for (const auto& c : commands())
    if (std::string p = formProblems(c.name, c.forms); !p.empty()) out += p + "\n";
  return out;
}

std::vector<std::string> Console::completions(const std::string& partial_line) const {
  std::vector<std::string> done = splitWords(partial_line);
  const bool at_blank = !partial_line.empty() && (partial_line.back() == ' ' || partial_line.back() == '\t');
  const std::string partial = at_blank || done.empty() ? "" : done.back();
  if (!at_blank && !done.empty()) done.pop_back();
  const bool tried = !done.empty() && done.front() == "try";  // 'try <command>'
  if (tried) done.erase(done.begin());
  std::vector<std::string> names;
  if (!tried) names.push_back("try");
  for (const auto& c : commands()) names.push_back(c.name);
  if (done.empty()) {
    std::vector<std::string> out;
    for (const auto& n : names)
      if (n.compare(0, partial.size(), partial) == 0) out.push_back(n);
    std::sort(out.begin(), out.end());
    return out;
  }
  const CommandDef* c = findCommand(done.front() == "?" ? "help" : done.front());
  if (!c) return {};
  std::vector<std::string> robots;
  for (const auto& r : registry_.snapshots(clock_->nowNs())) robots.push_back(r.id);
  const std::map<ArgSpec::Source, std::vector<std::string>> dynamic{{Source::kCommands, names},
                                                                    {Source::kRobots, robots}};
  return completeArgs(c->forms, {done.begin() + 1, done.end()}, partial, dynamic);
}

}  // namespace inspect::server
