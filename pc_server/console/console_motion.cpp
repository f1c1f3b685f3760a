// The console's motion and camera commands: drive, teleop, track, goto,
// route, stop, estop, resume; video, ptz, snapshot (docs/console.md).
#include "pc_server/console/console.hpp"

#include <cmath>
#include <cstdio>

#include "pc_server/console/route_file.hpp"
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
                         "panel; a set-point lapses 0.5 s after the last, docs/foxglove.md)");
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
  const uint64_t id = sink_.setTeleop(*robot, *v, *w, 0.0);  // held until stop (docs/failsafes.md)
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
  if (site_maps_ && !r.map.empty() && !selected_.empty()) site_maps_->set(selected_, r.map);
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
