// The console's motion and camera commands: drive, teleop, track, goto,
// route, stop, estop, resume; video, ptz, snapshot (docs/console.md).
#include "pc_server/console/motion_commands.hpp"

#include <cmath>
#include <cstdio>

#include "pc_server/console/console.hpp"
#include "pc_server/console/text_util.hpp"
#include "pc_server/operator/command_limits.hpp"
#include "pc_server/operator/route_file.hpp"
#include "pc_server/recording/recorder.hpp"
#include "pc_server/scene/site_maps.hpp"
#include "pc_server/video/video_hub.hpp"
#include "pc_server/video/video_streams.hpp"
#include "shared/config/config_node.hpp"
#include "shared/util/clock.hpp"

namespace inspect::server {

using namespace args;

namespace {
/// track's last argument: the tracking controller (default: the robot's config).
ArgSpec controller() {
  ArgSpec a = choice("controller", {"fuzzy_pid", "pid", "direct"}, "controller");
  a.shown = "<controller>";
  return a;
}
}  // namespace

bool MotionCommands::cmdDrive(const CommandArgs& a) {
  if (!c_.options().allow_drive)
    return c_.fail("drive", "not from a Foxglove session: publish geometry_msgs/Twist on /<robot>/cmd_vel (the Teleop "
                         "panel; a set-point lapses foxglove.teleop_timeout_s after the last, docs/foxglove.md)");
  const double v = *a.number("v_m_s"), w = *a.number("w_rad_s");
  const std::string what = "drive " + fmtSigned(v) + " m/s " + fmtSigned(w) + " rad/s";
  // A typed `drive` is meant to last: held until stop on the server's own
  // console (its thread is watched); while the operator is present (leased,
  // renewed by operatorPresent) on an attached one (docs/failsafes.md).
  const double lease = c_.options().drive_lease_s;
  const CallResult r = c_.outcomeOf(c_.service().teleop(c_.session(), c_.selected(), v, w, lease, c_.clock().nowNs()));
  if (r.outcome == CallOutcome::kInvalid || r.outcome == CallOutcome::kRefused) return c_.report(r);  // nothing sent
  if (!r.ok()) {
    c_.service().clearTeleop(r.robot);
    c_.countError();
    if (r.outcome == CallOutcome::kTimedOut)
      c_.out() << r.robot << ": " << what << ": no ack within " << fmtShort(r.ack_timeout_s) << " s (set-point cleared)\n";
    else
      c_.out() << r.robot << ": " << what << " rejected: " << r.reason << "\n";
    return false;
  }
  c_.setDriveRobot(r.robot);
  c_.out() << r.robot << ": " << what << " accepted ("
       << (lease > 0 ? "re-sent while this session is active; it lapses " + fmtShort(lease) + " s after its last input"
                     : std::string("re-sent until stop"))
       << ")\n";
  return true;
}

bool MotionCommands::cmdTeleop(const CommandArgs& a) {
  TeleopMode mode = TeleopMode::kStep;
  if (a.has("mode")) parseTeleopMode(a.text("mode"), mode);  // the table accepts only step and hold
  if (!c_.teleopHandler()) return c_.fail("teleop", "keyboard teleop needs an interactive terminal (scripts use drive)");
  const auto robot = c_.connectedRobot("teleop");
  if (!robot || !c_.mayMove(*robot, "teleop")) return false;
  if (!c_.teleopHandler()(mode, *robot)) {
    c_.countError();
    return false;
  }
  return true;
}

bool MotionCommands::cmdTrack(const CommandArgs& a) {
  TrackRequest t;
  t.controller = a.text("controller");
  t.speed_m_s = a.number("speed_m_s", 0.5);
  if (a.has("circle")) {
    t.shape = TrackRequest::Shape::kCircle;
    t.size_m = *a.number("radius_m");
    t.laps = a.number("laps", 1.0);
  } else {
    t.shape = TrackRequest::Shape::kLine;
    t.size_m = *a.number("length_m");
  }
  return c_.report(c_.service().track(c_.session(), c_.selected(), t, c_.clock().nowNs()), true);
}

bool MotionCommands::cmdGoto(const CommandArgs& a) {
  return c_.report(c_.service().goTo(c_.session(), c_.selected(), *a.number("x_m"), *a.number("y_m"), a.number("speed_m_s"),
                               c_.clock().nowNs(), a.has("force")),
                true);
}

bool MotionCommands::cmdRoute(const CommandArgs& a) {
  Route r;
  try {
    r = openRoute(a.text("file|name"));
  } catch (const config::ConfigError& e) {
    return c_.fail("route", e.what());
  }
  std::string summary;
  const Issued issued = c_.service().route(c_.session(), c_.selected(), r, c_.clock().nowNs(), &summary);
  c_.out() << summary << "\n";
  return c_.report(issued, true);
}

bool MotionCommands::cmdStop(const CommandArgs&) {
  v1::Command c;
  c.mutable_stop();
  return c_.sendAndReport("stop", c);
}

bool MotionCommands::cmdEstop(const CommandArgs&) {
  v1::Command c;
  c.mutable_estop();
  return c_.sendAndReport("estop", c);
}

bool MotionCommands::cmdResume(const CommandArgs&) {
  v1::Command c;
  c.mutable_resume();
  return c_.sendAndReport("resume", c);
}

bool MotionCommands::cmdVideo(const CommandArgs& a) {
  using W = VideoRequest::What;
  VideoRequest v;
  const std::string& what = a.words.front();  // the form's first word
  if (what == "stats") {
    const auto robot = c_.connectedRobot("video");
    if (!robot) return false;
    c_.out() << videoReport(*robot, c_.registry().snapshot(*robot, c_.clock().nowNs()), c_.video());
    return true;
  }
  if (a.has("res")) {
    v.what = W::kRes;
    v.width = static_cast<long long>(*a.number("size.w"));
    v.height = static_cast<long long>(*a.number("size.h"));
  } else if (a.has("fps")) {
    v.what = W::kFps;
    v.fps = *a.number("n");
  } else if (a.has("bitrate")) {
    v.what = W::kBitrate;
    v.bitrate_kbps = static_cast<long long>(*a.number("kbit/s"));
  } else {
    const std::string& w = a.has("wide") ? a.text("what") : what;
    v.what = w == "on" ? W::kOn : w == "off" ? W::kOff : W::kKeyframe;
  }
  if (a.has("wide")) v.head = v1::WIDE_HEAD;
  return c_.report(c_.service().video(c_.session(), c_.selected(), v, c_.clock().nowNs()));
}

bool MotionCommands::cmdPtz(const CommandArgs& a) {
  PtzRequest p;
  p.home = a.has("home");
  p.pan_deg = a.number("pan_deg", 0.0);
  p.tilt_deg = a.number("tilt_deg", 0.0);
  return c_.report(c_.service().ptz(c_.session(), c_.selected(), p, c_.clock().nowNs()));
}

bool MotionCommands::cmdFoxglove(const CommandArgs&) {
  if (!c_.foxgloveReport()) return c_.fail("foxglove", "the server has no Foxglove bridge (foxglove.enabled: false or --no-foxglove)");
  c_.out() << c_.foxgloveReport()();
  return true;
}

bool MotionCommands::cmdSparkplug(const CommandArgs&) {
  if (!c_.sparkplugReport())
    return c_.fail("sparkplug", "the server is no Sparkplug edge node (sparkplug.enabled: false; --sparkplug-broker)");
  c_.out() << c_.sparkplugReport()();
  return true;
}

bool MotionCommands::cmdSnapshot(const CommandArgs& a) {
  if (!c_.video()) return c_.fail("snapshot", "the server runs without video (video.enabled: false or --no-video)");
  if (c_.selected().empty()) return c_.fail("snapshot", "no robot selected");
  try {
    const std::string path = c_.video()->snapshot(
        streamName(c_.selected(), a.has("wide") ? v1::WIDE_HEAD : v1::PTZ_HEAD), a.text("file.png"));
    c_.out() << c_.selected() << ": snapshot " << path << "\n";
    return true;
  } catch (const std::exception& e) {
    return c_.fail("snapshot", e.what());
  }
}

// Commands of moving the robot and its camera.
std::vector<ConsoleCommand> MotionCommands::commands() {
  return {
    {"drive", {{number("v_m_s"), number("w_rad_s")}}, "set the teleop set-point; re-sent at teleop_resend_hz until stop",
     "  v in [-1, 1] m/s (forward positive), w in [-2, 2] rad/s (counter-clockwise positive).\n"
     "  The server re-sends the set-point (default 20 Hz) so the robot's 300 ms deadman stays\n"
     "  quiet while the console and link work; in an attached console (--attach) it lapses\n"
     "  0.3 s after the session's last line or keep-alive. Waits up to 1 s for the robot's Ack of the first\n"
     "  command; a rejection or no Ack clears the set-point and is an error.\n"
     "  example: drive 0.3 0      (straight ahead at 0.3 m/s)\n"
     "  example: drive 0 0.5      (turn on the spot, 0.5 rad/s to the left)\n",
     handler(this, &MotionCommands::cmdDrive)},
    {"teleop", {{opt(choice("mode", {"step", "hold"}, "mode"))}}, "keyboard teleop (interactive terminal only)",
     "  step (default): w/s or Up/Down step v by 0.05 m/s, a/d or Left/Right step w by 0.1 rad/s\n"
     "    (clamped to +-1.0 m/s, +-2.0 rad/s); the set-point stays until changed.\n"
     "  hold: hold w/s/a/d (or arrows) to drive at 0.3 m/s or 1.0 rad/s; releasing the key\n"
     "    zeroes the set-point (deadman: 300 ms before the first auto-repeat, 200 ms after).\n"
     "  Both: space (or x, 0) zeroes at once; q or Esc leaves teleop and sends stop.\n",
     handler(this, &MotionCommands::cmdTeleop)},
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
     handler(this, &MotionCommands::cmdTrack)},
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
     handler(this, &MotionCommands::cmdGoto)},
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
     handler(this, &MotionCommands::cmdRoute)},
    {"stop", noArguments(), "zero the set-point and stop re-sending (not latched)",
     "  Prints the robot's answer: 'robot1: stop accepted', '... rejected: <reason>' or\n"
     "  'robot1: no ack within 1 s' (the last two are errors).\n",
     handler(this, &MotionCommands::cmdStop)},
    {"estop", noArguments(), "emergency stop, latched until resume",
     "  Clears the set-point and sends EStop; waits up to 1 s for the Ack.\n", handler(this, &MotionCommands::cmdEstop)},
    {"resume", noArguments(), "clear a latched e-stop or failsafe",
     "  Waits up to 1 s for the Ack; e.g. 'robot1: resume rejected: <reason>'.\n", handler(this, &MotionCommands::cmdResume)},
    {"video",
     {{choice("what", {"on", "off", "keyframe", "stats"})},
      {keyword("res"), wanting(size("size"), kVideoSizeWant)},
      {keyword("fps"), wanting(number("n"), kVideoFpsWant)},
      {keyword("bitrate"), wanting(integer("kbit/s"), kVideoBitrateWant)},
      {keyword("wide"), choice("what", {"on", "off", "keyframe"})},
      {keyword("wide"), keyword("bitrate"), wanting(integer("kbit/s"), kVideoBitrateWant)}},
     "control the selected robot's camera streams; show their figures",
     "  on/off start and stop streaming; keyframe asks for an IDR now (the server also asks by\n"
     "  itself, at most every 0.3 s, when it lost part of a picture).\n"
     "  res: even width and height, 64 to 4096 (e.g. 1280x720); fps: 1 to 120; bitrate: 50 to\n"
     "  50000 kbit/s. A new size or bitrate restarts the robot's encoder with an IDR.\n"
     "  stats: received/decoded fps, kbit/s, packet loss, glass-to-glass latency (mean, p50, p99),\n"
     "  counters, the SDP file for players, and the robot's encoder figures.\n"
     "  Play the stream elsewhere: ffplay -protocol_whitelist file,udp,rtp -fflags nobuffer\n"
     "    -flags low_delay video/robot1.sdp   (the server forwards the RTP to the SDP's port)\n"
     "  wide ...: the same for the wide head's stream, on a robot that streams it\n"
     "  (wide_head.stream; video/robot1.wide.sdp); stats shows both.\n"
     "  example: video res 1280x720\n"
     "  example: video wide bitrate 500\n",
     handler(this, &MotionCommands::cmdVideo)},
    {"ptz", {{number("pan_deg"), number("tilt_deg")}, {keyword("home")}}, "point the camera mount (sent to the MCU)",
     "  pan counter-clockwise positive, [-180, 180] degrees; tilt up positive, [-90, 90].\n"
     "  example: ptz 30 -10\n",
     handler(this, &MotionCommands::cmdPtz)},
    {"snapshot", {{keyword("wide"), opt(word("file.png"))}, {opt(word("file.png"))}},
     "save the selected robot's latest decoded picture as PNG",
     "  Default file: <video.dir>/<robot>_<n>.png. Without a display the server also keeps\n"
     "  <video.dir>/<robot>_latest.png fresh (video.snapshot_period_s).\n"
     "  snapshot wide: the wide head's picture (<robot>.wide_<n>.png), when the robot streams it.\n",
     handler(this, &MotionCommands::cmdSnapshot)},
    {"foxglove", noArguments(), "the Foxglove bridge: clients, subscriptions, send queues, drops",
     "  One line per connected Foxglove/Lichtblick client (its operator session, how long it has\n"
     "  been connected, subscriptions, queued messages and bytes, messages sent, data and video\n"
     "  messages dropped for a slow reader, its messages refused), then the topics it subscribed\n"
     "  to and publishes on. docs/foxglove.md.\n",
     handler(this, &MotionCommands::cmdFoxglove)},
    {"sparkplug", noArguments(), "the SCADA edge node: broker, births, alarm transitions queued and sent",
     "  The MQTT Sparkplug B edge node (sparkplug: in server.yaml): the broker and whether the node\n"
     "  is born there (bdSeq, sessions), robots online, messages published, alarm transitions the\n"
     "  broker confirmed, still queued (a broker outage) and dropped, DCMD received and refused,\n"
     "  and why the last session ended. docs/sparkplug.md.\n",
     handler(this, &MotionCommands::cmdSparkplug)},
  };
}

}  // namespace inspect::server
