// The console's motion and camera commands: drive, teleop, track, goto,
// route, stop, estop, resume; video, ptz, snapshot (docs/console.md).
#include "pc_server/console/console.hpp"

#include <cmath>
#include <cstdio>

#include "pc_server/operator/route_file.hpp"
#include "pc_server/console/text_util.hpp"
#include "pc_server/recording/recorder.hpp"
#include "pc_server/scene/site_maps.hpp"
#include "pc_server/video/video_hub.hpp"
#include "shared/config/config_node.hpp"
#include "shared/util/clock.hpp"

namespace inspect::server {

bool Console::cmdDrive(const Args& args, const std::string&, int) {
  if (!options_.allow_drive)
    return fail("drive", "not from a Foxglove session: publish geometry_msgs/Twist on /<robot>/cmd_vel (the Teleop "
                         "panel; a set-point lapses foxglove.teleop_timeout_s after the last, docs/foxglove.md)");
  if (args.size() != 2) return fail("drive", "needs two numbers: drive <v_m_s> <w_rad_s>");
  const auto v = parseNumber(args[0]);
  if (!v) return fail("drive", "'" + args[0] + "' is not a number");
  const auto w = parseNumber(args[1]);
  if (!w) return fail("drive", "'" + args[1] + "' is not a number");
  const std::string what = "drive " + fmtSigned(*v) + " m/s " + fmtSigned(*w) + " rad/s";
  // A typed `drive` is meant to last: held until stop on the server's own
  // console (its thread is watched); while the operator is present (leased,
  // renewed by operatorPresent) on an attached one (docs/failsafes.md).
  const double lease = options_.drive_lease_s;
  const CallResult r = outcomeOf(service_->teleop(session_, selected_, *v, *w, lease, clock_->nowNs()));
  if (r.outcome == CallOutcome::kInvalid || r.outcome == CallOutcome::kRefused) return report(r);  // nothing sent
  if (!r.ok()) {
    service_->clearTeleop(r.robot);
    ++tally_.errors;
    if (r.outcome == CallOutcome::kTimedOut)
      out_ << r.robot << ": " << what << ": no ack within " << fmtShort(r.ack_timeout_s) << " s (set-point cleared)\n";
    else
      out_ << r.robot << ": " << what << " rejected: " << r.reason << "\n";
    return false;
  }
  drive_robot_ = r.robot;
  out_ << r.robot << ": " << what << " accepted ("
       << (lease > 0 ? "re-sent while this session is active; it lapses " + fmtShort(lease) + " s after its last input"
                     : std::string("re-sent until stop"))
       << ")\n";
  return true;
}

void Console::operatorPresent() { service_->renewTeleop(session_, drive_robot_, options_.drive_lease_s); }

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

bool Console::simpleCommand(const std::string& name, const Args& args, v1::Command cmd) {
  if (!args.empty()) return fail(name, "takes no arguments");
  return sendAndReport(name, std::move(cmd));
}

bool Console::sendAndReport(const std::string& name, v1::Command cmd, bool runs) {
  return report(service_->send(session_, selected_, name, std::move(cmd), clock_->nowNs()), runs);
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
  TrackRequest t;
  t.controller = controller;
  t.speed_m_s = nums.size() > 1 ? nums[1] : 0.5;
  if (args[0] == "circle") {
    if (nums.empty() || nums.size() > 3) return fail("track", kSyntax);
    t.shape = TrackRequest::Shape::kCircle;
    t.laps = nums.size() > 2 ? nums[2] : 1.0;
  } else if (args[0] == "line") {
    if (nums.empty() || nums.size() > 2) return fail("track", kSyntax);
    t.shape = TrackRequest::Shape::kLine;
  } else {
    return fail("track", "unknown path '" + args[0] + "' (circle or line)");
  }
  t.size_m = nums[0];
  return report(service_->track(session_, selected_, t, clock_->nowNs()), true);
}

bool Console::cmdGoto(const Args& args, const std::string&, int) {
  if (args.size() < 2 || args.size() > 3) return fail("goto", "needs two or three numbers: goto <x_m> <y_m> [speed_m_s]");
  std::vector<double> nums;
  for (const auto& a : args) {
    const auto v = parseNumber(a);
    if (!v) return fail("goto", "'" + a + "' is not a number");
    nums.push_back(*v);
  }
  const std::optional<double> speed = nums.size() > 2 ? std::optional<double>(nums[2]) : std::nullopt;
  return report(service_->goTo(session_, selected_, nums[0], nums[1], speed, clock_->nowNs()), true);
}

bool Console::cmdRoute(const Args& args, const std::string&, int) {
  if (args.size() != 1) return fail("route", "needs one route: route <file|name>");
  Route r;
  try {
    r = openRoute(args[0]);
  } catch (const config::ConfigError& e) {
    return fail("route", e.what());
  }
  std::string summary;
  const Issued issued = service_->route(session_, selected_, r, clock_->nowNs(), &summary);
  out_ << summary << "\n";
  return report(issued, true);
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
  using W = VideoRequest::What;
  VideoRequest v;
  if ((what == "on" || what == "off" || what == "keyframe") && args.size() == 1) {
    v.what = what == "on" ? W::kOn : what == "off" ? W::kOff : W::kKeyframe;
    return report(service_->video(session_, selected_, v, clock_->nowNs()));
  }
  if (what != "res" && what != "fps" && what != "bitrate" && what != "on" && what != "off" && what != "keyframe")
    return fail("video", "unknown '" + what + "'; " + kSyntax);
  if (args.size() != 2) return fail("video", kSyntax);
  if (what == "res") {
    const auto x = args[1].find('x');
    const auto w = x == std::string::npos ? std::nullopt : parseInteger(args[1].substr(0, x));
    const auto h = x == std::string::npos ? std::nullopt : parseInteger(args[1].substr(x + 1));
    if (!w || !h) return fail("video", "res '" + args[1] + "': want <W>x<H>, even, 64 to 4096 (e.g. 1280x720)");
    v.what = W::kRes;
    v.width = *w;
    v.height = *h;
  } else if (what == "fps") {
    const auto f = parseNumber(args[1]);
    if (!f) return fail("video", "fps '" + args[1] + "': want 1 to 120");
    v.what = W::kFps;
    v.fps = *f;
  } else if (what == "bitrate") {
    const auto b = parseInteger(args[1]);
    if (!b) return fail("video", "bitrate '" + args[1] + "': want 50 to 50000 kbit/s");
    v.what = W::kBitrate;
    v.bitrate_kbps = *b;
  } else {
    return fail("video", "unknown '" + what + "'; " + kSyntax);
  }
  return report(service_->video(session_, selected_, v, clock_->nowNs()));
}

bool Console::cmdPtz(const Args& args, const std::string&, int) {
  PtzRequest p;
  if (args.size() == 1 && args[0] == "home") {
    p.home = true;
    return report(service_->ptz(session_, selected_, p, clock_->nowNs()));
  }
  const auto pan = args.size() == 2 ? parseNumber(args[0]) : std::nullopt;
  const auto tilt = args.size() == 2 ? parseNumber(args[1]) : std::nullopt;
  if (!pan || !tilt) return fail("ptz", "syntax: ptz <pan_deg> <tilt_deg> | ptz home");
  p.pan_deg = *pan;
  p.tilt_deg = *tilt;
  return report(service_->ptz(session_, selected_, p, clock_->nowNs()));
}

bool Console::cmdFoxglove(const Args& args, const std::string&, int) {
  if (!args.empty()) return fail("foxglove", "takes no arguments");
  if (!foxglove_report_) return fail("foxglove", "the server has no Foxglove bridge (foxglove.enabled: false or --no-foxglove)");
  out_ << foxglove_report_();
  return true;
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

}  // namespace inspect::server
