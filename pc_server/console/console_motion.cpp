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

bool Console::cmdDrive(const CommandArgs& a) {
  if (!options_.allow_drive)
    return fail("drive", "not from a Foxglove session: publish geometry_msgs/Twist on /<robot>/cmd_vel (the Teleop "
                         "panel; a set-point lapses foxglove.teleop_timeout_s after the last, docs/foxglove.md)");
  const double v = *a.number("v_m_s"), w = *a.number("w_rad_s");
  const std::string what = "drive " + fmtSigned(v) + " m/s " + fmtSigned(w) + " rad/s";
  // A typed `drive` is meant to last: held until stop on the server's own
  // console (its thread is watched); while the operator is present (leased,
  // renewed by operatorPresent) on an attached one (docs/failsafes.md).
  const double lease = options_.drive_lease_s;
  const CallResult r = outcomeOf(service_->teleop(session_, selected_, v, w, lease, clock_->nowNs()));
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

bool Console::cmdTeleop(const CommandArgs& a) {
  TeleopMode mode = TeleopMode::kStep;
  if (a.has("mode")) parseTeleopMode(a.text("mode"), mode);  // the table accepts only step and hold
  if (!teleop_handler_) return fail("teleop", "keyboard teleop needs an interactive terminal (scripts use drive)");
  const auto robot = connectedRobot("teleop");
  if (!robot || !mayMove(*robot, "teleop")) return false;
  if (!teleop_handler_(mode, *robot)) {
    ++tally_.errors;
    return false;
  }
  return true;
}

bool Console::sendAndReport(const std::string& name, v1::Command cmd, bool runs) {
  return report(service_->send(session_, selected_, name, std::move(cmd), clock_->nowNs()), runs);
}

bool Console::cmdTrack(const CommandArgs& a) {
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
  return report(service_->track(session_, selected_, t, clock_->nowNs()), true);
}

bool Console::cmdGoto(const CommandArgs& a) {
  return report(service_->goTo(session_, selected_, *a.number("x_m"), *a.number("y_m"), a.number("speed_m_s"),
                               clock_->nowNs(), a.has("force")),
                true);
}

bool Console::cmdRoute(const CommandArgs& a) {
  Route r;
  try {
    r = openRoute(a.text("file|name"));
  } catch (const config::ConfigError& e) {
    return fail("route", e.what());
  }
  std::string summary;
  const Issued issued = service_->route(session_, selected_, r, clock_->nowNs(), &summary);
  out_ << summary << "\n";
  return report(issued, true);
}

bool Console::cmdStop(const CommandArgs&) {
  v1::Command c;
  c.mutable_stop();
  return sendAndReport("stop", c);
}

bool Console::cmdEstop(const CommandArgs&) {
  v1::Command c;
  c.mutable_estop();
  return sendAndReport("estop", c);
}

bool Console::cmdResume(const CommandArgs&) {
  v1::Command c;
  c.mutable_resume();
  return sendAndReport("resume", c);
}

bool Console::cmdVideo(const CommandArgs& a) {
  using W = VideoRequest::What;
  VideoRequest v;
  const std::string& what = a.words.front();  // the form's first word
  if (what == "stats") {
    const auto robot = connectedRobot("video");
    if (!robot) return false;
    out_ << videoReport(*robot, registry_.snapshot(*robot, clock_->nowNs()), video_);
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
    v.what = what == "on" ? W::kOn : what == "off" ? W::kOff : W::kKeyframe;
  }
  return report(service_->video(session_, selected_, v, clock_->nowNs()));
}

bool Console::cmdPtz(const CommandArgs& a) {
  PtzRequest p;
  p.home = a.has("home");
  p.pan_deg = a.number("pan_deg", 0.0);
  p.tilt_deg = a.number("tilt_deg", 0.0);
  return report(service_->ptz(session_, selected_, p, clock_->nowNs()));
}

bool Console::cmdFoxglove(const CommandArgs&) {
  if (!foxglove_report_) return fail("foxglove", "the server has no Foxglove bridge (foxglove.enabled: false or --no-foxglove)");
  out_ << foxglove_report_();
  return true;
}

bool Console::cmdSnapshot(const CommandArgs& a) {
  if (!video_) return fail("snapshot", "the server runs without video (video.enabled: false or --no-video)");
  if (selected_.empty()) return fail("snapshot", "no robot selected");
  try {
    const std::string path = video_->snapshot(selected_, a.text("file.png"));
    out_ << selected_ << ": snapshot " << path << "\n";
    return true;
  } catch (const std::exception& e) {
    return fail("snapshot", e.what());
  }
}

}  // namespace inspect::server
