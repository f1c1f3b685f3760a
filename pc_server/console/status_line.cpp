#include "pc_server/console/status_line.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>

#include "pc_server/console/expect_check.hpp"
#include "pc_server/console/text_util.hpp"
#include "pc_server/video/video_hub.hpp"
#include "pc_server/video/video_streams.hpp"

namespace inspect::server {

std::string faultNames(uint32_t faults) {
  if (faults == 0) return "none";
  std::string s;
  for (uint32_t bit = 1; bit != 0; bit <<= 1) {
    if (!(faults & bit)) continue;
    std::string name = v1::Fault_IsValid(static_cast<int>(bit)) ? v1::Fault_Name(static_cast<v1::Fault>(bit))
                                                                : "bit" + std::to_string(bit);
    if (name.rfind("FAULT_", 0) == 0) name.erase(0, 6);
    s += (s.empty() ? "" : ",") + name;
  }
  return s;
}

namespace {
// The robot's rate in force and why it last changed (rate adaptation), "" when it does not adapt.
std::string rateNote(const v1::VideoStatus& tv) {
  if (!tv.adapt() || tv.rate_kbps() == 0) return {};
  std::string s = " | rate " + std::to_string(tv.rate_kbps()) + " kbit/s";
  if (tv.rate_level() > 0)
    s += " " + std::to_string(tv.send_width()) + "x" + std::to_string(tv.send_height()) + "@" + fmtShort(tv.send_fps());
  return s + " (" + tv.rate_reason() + ")";
}

const char* perceptionName(v1::PerceptionMode m) {
  switch (m) {
    case v1::CAMERA_AND_SONAR: return "camera+sonar";
    case v1::CAMERA_ELSEWHERE: return "camera elsewhere, sonar";
    default: return "sonar only";
  }
}

// The people the camera sees now: "2 seen: +5 deg 5.1 m, -12 deg".
std::string seenPeople(const v1::Perception& p) {
  std::string s = std::to_string(p.people_size()) + " seen";
  for (int i = 0; i < p.people_size(); ++i) {
    const auto& q = p.people(i);
    s += (i ? ", " : ": ") + fmtSigned(q.bearing_rad() * 180.0 / M_PI, 0) + " deg";
    if (q.has_range_m()) s += " " + fmtFixed(q.range_m(), 1) + " m";
  }
  return s;
}

// One head's detection: what it sees now, its detector and pace.
std::string headFigures(const v1::Perception& p) {
  return std::string(perceptionName(p.mode())) + ", " + seenPeople(p) + "; " + p.detector() + " on " +
         std::to_string(p.width()) + "x" + std::to_string(p.height()) + ", " + fmtFixed(p.rate_hz(), 1) + " Hz, " +
         fmtFixed(p.detect_ms(), 1) + " ms, " + std::to_string(p.detections()) + " pictures" +
         (p.looking_ahead() ? ", looking ahead for people" : "") +
         (p.looking_aside() ? ", looking aside at a sonar track" : "") +
         (p.aside_looks() ? ", " + std::to_string(p.aside_looks()) + " looks aside (" +
                                fmtFixed(p.aside_off_path_s(), 1) + " s off the path)"
                          : "") +
         (p.error().empty() ? "" : ", error: " + p.error());
}

std::string videoFigures(const RobotSnapshot& snap, const VideoHub* video) {
  if (!snap.telemetry.has_video()) return {};
  const auto& tv = snap.telemetry.video();
  if (!tv.enabled()) return " | video off";
  const auto st = video ? video->stats(snap.id) : std::nullopt;
  if (!st || !st->active)
    return " | video no packets" + (tv.error().empty() ? std::string() : " (" + tv.error() + ")") + rateNote(tv);
  return " | video " + fmtFixed(st->fps_received, 0) + "/" + fmtFixed(st->fps_decoded, 0) + " fps " +
         fmtFixed(st->kbps, 0) + " kbit/s loss " + fmtFixed(st->loss_pct, 1) + "% lat " +
         (st->latency_ms < 0 ? std::string("--") : fmtFixed(st->latency_ms, 0)) + " ms" + rateNote(tv);
}

/// "ffplay ... robot1.sdp   (RTP forwarded to 127.0.0.1:5700)" for a stream seen.
std::string playLine(const VideoHub& video, const std::string& stream) {
  const auto sdp = video.sdpPath(stream);
  if (sdp.empty()) return {};
  return ffplayCommand(sdp) + "   (RTP forwarded to 127.0.0.1:" + std::to_string(video.forwardPort(stream)) + ")";
}

/// The wide head's stream (docs/video.md "The wide head's stream"): the robot's and the server's figures.
template <typename Line>
void wideStreamLines(const Line& line, const std::string& robot_id, const v1::VideoStatus& v, const VideoHub& video) {
  line("wide stream", std::string(v.enabled() ? "on" : "off") + ", " + v.source() + " " + std::to_string(v.width()) +
                          "x" + std::to_string(v.height()) + " @ " + fmtShort(v.fps()) + " fps, " + v.encoder() + " " +
                          std::to_string(v.rate_kbps() ? v.rate_kbps() : v.bitrate_kbps()) + " kbit/s, SSRC " +
                          std::to_string(v.ssrc()) + "; captured " + std::to_string(v.frames_captured()) +
                          ", encoded " + std::to_string(v.frames_encoded()) + ", dropped " +
                          std::to_string(v.frames_dropped()) + (v.error().empty() ? "" : "; error: " + v.error()));
  const std::string name = streamName(robot_id, v1::WIDE_HEAD);
  if (const auto st = video.stats(name))
    line("wide received", fmtFixed(st->fps_received, 1) + " fps, decoded " + fmtFixed(st->fps_decoded, 1) + " fps, " +
                              fmtFixed(st->kbps, 0) + " kbit/s, loss " + fmtFixed(st->loss_pct, 2) + "%, " +
                              std::to_string(st->width) + "x" + std::to_string(st->height) + ", latency p50 " +
                              fmtFixed(st->latency_p50_ms, 1) + " ms, p99 " + fmtFixed(st->latency_p99_ms, 1) +
                              " ms, frames " + std::to_string(st->frames) + ", lost packets " +
                              std::to_string(st->lost_packets));
  else
    line("wide received", "no stream yet");
  if (const auto play = playLine(video, name); !play.empty()) line("wide play", play);
}
}  // namespace

std::string videoReport(const std::string& robot_id, const std::optional<RobotSnapshot>& snap, const VideoHub* video) {
  std::string s;
  const auto line = [&s](const std::string& k, const std::string& v) { s += "  " + k + ": " + v + "\n"; };
  s += robot_id + " video\n";
  if (snap && snap->has_telemetry && snap->telemetry.has_video()) {
    const auto& v = snap->telemetry.video();
    line("robot", std::string(v.enabled() ? "on" : "off") + ", " + v.source() + " " + std::to_string(v.width()) + "x" +
                      std::to_string(v.height()) + " @ " + fmtShort(v.fps()) + " fps, " + v.encoder() + " " +
                      std::to_string(v.bitrate_kbps()) + " kbit/s, SSRC " + std::to_string(v.ssrc()) + ", to UDP port " +
                      std::to_string(v.port()));
    line("robot frames", "captured " + std::to_string(v.frames_captured()) + ", encoded " +
                             std::to_string(v.frames_encoded()) + ", dropped " + std::to_string(v.frames_dropped()) +
                             ", keyframes " + std::to_string(v.keyframes()) + " (" +
                             std::to_string(v.keyframe_requests()) + " requested), encode " +
                             fmtFixed(v.encode_ms(), 1) + " ms/frame");
    if (v.rate_kbps() != 0) {
      std::string rate = std::to_string(v.rate_kbps()) + " kbit/s, " + std::to_string(v.send_width()) + "x" +
                         std::to_string(v.send_height()) + " @ " + fmtShort(v.send_fps()) + " fps";
      if (v.adapt())
        rate += " (adapting in " + std::to_string(v.min_kbps()) + "-" + std::to_string(v.max_kbps()) + " kbit/s, level " +
                std::to_string(v.rate_level()) + "); last change " + fmtFixed(v.rate_age_s(), 1) + " s ago: " +
                v.rate_reason() + " (" + std::to_string(v.rate_changes()) + " changes)";
      else
        rate += " (adaptation off)";
      line("robot rate", rate);
      line("robot feedback", "receiver's loss " + (v.peer_loss_pct() < 0 ? std::string("-") : fmtFixed(v.peer_loss_pct(), 1) + " %") +
                                 ", RTT " + (v.rtt_ms() < 0 ? std::string("-") : fmtFixed(v.rtt_ms(), 1) + " ms") +
                                 ", NACKed " + std::to_string(v.nacked_packets()) + ", retransmitted " +
                                 std::to_string(v.retransmitted()) + ", repeat NACKs " +
                                 std::to_string(v.repeat_nacks()) + ", not in history " +
                                 std::to_string(v.not_in_history()));
    }
    if (!v.error().empty()) line("robot error", v.error());
    if (snap->telemetry.has_perception())
      line("robot people", headFigures(snap->telemetry.perception()));
    else
      line("robot people", "sonar only (no detector on the robot)");
    if (snap->telemetry.has_wide_perception()) line("robot wide head", headFigures(snap->telemetry.wide_perception()));
  } else {
    line("robot", "no video in telemetry");
  }
  if (!video) {
    line("server", "video off (video.enabled: false or --no-video)");
    return s;
  }
  const auto st = video->stats(robot_id);
  if (!st) {
    line("server", "no stream yet");
  } else {
    line("received", fmtFixed(st->fps_received, 1) + " fps, decoded " + fmtFixed(st->fps_decoded, 1) + " fps, " +
                         fmtFixed(st->kbps, 0) + " kbit/s, loss " + fmtFixed(st->loss_pct, 2) + "%, " +
                         std::to_string(st->width) + "x" + std::to_string(st->height));
    line("latency", "mean " + fmtFixed(st->latency_ms, 1) + " ms (last second), p50 " + fmtFixed(st->latency_p50_ms, 1) +
                        " ms, p99 " + fmtFixed(st->latency_p99_ms, 1) + " ms (last 300 frames)");
    line("counters", "packets " + std::to_string(st->packets) + ", lost " + std::to_string(st->lost_packets) +
                         ", duplicates " + std::to_string(st->duplicates) + ", late " + std::to_string(st->late) +
                         ", frames " + std::to_string(st->frames) + ", dropped " + std::to_string(st->frames_dropped) +
                         ", decoded " + std::to_string(st->decoded) + ", skipped awaiting a keyframe " +
                         std::to_string(st->frames_skipped) + ", decode errors " +
                         std::to_string(st->decode_errors) + ", keyframe requests " +
                         std::to_string(st->keyframe_requests));
    line("repair", "NACKs " + std::to_string(st->nacks_sent) + " for " + std::to_string(st->nacked_packets) +
                       " packets, retransmissions " + std::to_string(st->retransmissions) + ", unneeded " +
                       std::to_string(st->rtx_unneeded) + ", tail probes " + std::to_string(st->tail_probes) +
                       ", PLIs " + std::to_string(st->plis_sent) + ", RTT " +
                       (st->rtt_ms < 0 ? std::string("-") : fmtFixed(st->rtt_ms, 1) + " ms"));
  }
  const auto c = video->counters();
  line("rejected datagrams", "not RTP " + std::to_string(c.not_rtp) + ", unknown SSRC " + std::to_string(c.unknown_ssrc) +
                                 ", wrong source " + std::to_string(c.wrong_source) + ", wrong payload type " +
                                 std::to_string(c.wrong_payload_type) +
                                 (c.last_reject.empty() ? std::string() : " (last: " + c.last_reject + ")"));
  if (const auto play = playLine(*video, robot_id); !play.empty()) line("play", play);
  if (snap && snap->has_telemetry && snap->telemetry.has_wide_video())
    wideStreamLines(line, robot_id, snap->telemetry.wide_video(), *video);
  return s;
}

std::string statusLine(const std::string& robot_id, const std::optional<RobotSnapshot>& snap, const VideoHub* video) {
  if (!snap) return robot_id + " | not connected yet";
  std::string s = robot_id;
  if (!snap->connected)
    s += " | DISCONNECTED " + fmtFixed(snap->state_age_s, 1) + " s ago (" + snap->close_reason + ")";
  if (!snap->has_telemetry) return s + (snap->connected ? " | connected, no telemetry yet" : "");
  const auto& t = snap->telemetry;
  // A field the robot left out is unknown (link protocol 2, "Presence"): shown so, never as 0.
  const auto known = [](bool has, double v, std::string (*fmt)(double, int), int digits) {
    return has ? fmt(v, digits) : std::string(kUnknown);
  };
  s += " | " + modeName(t.mode());
  s += " | v " + known(t.has_v_m_s(), t.v_m_s(), fmtSigned, 2) + " w " + known(t.has_w_rad_s(), t.w_rad_s(), fmtSigned, 2);
  s += " | x " + fmtFixed(t.pose().x_m()) + " y " + fmtFixed(t.pose().y_m()) + " th " + fmtSigned(t.pose().theta_rad());
  if (t.mode() == v1::TRACKING)
    s += " | " + t.track_controller() + " " + known(t.has_track_progress(), 100.0 * t.track_progress(), fmtFixed, 0) +
         "% err " + known(t.has_position_error_m(), t.position_error_m(), fmtFixed, 3) + " m " +
         known(t.has_angle_error_rad(), t.angle_error_rad(), fmtFixed, 3) + " rad kp " +
         known(t.has_kp(), t.kp(), fmtFixed, 1);
  if (t.mode() == v1::NAVIGATING) {
    char nav[96];
    std::snprintf(nav, sizeof nav, " goal %u/%u %s m sw %u", t.goal_index() + 1, t.goal_count(),
                  known(t.has_goal_distance_m(), t.goal_distance_m(), fmtFixed, 2).c_str(), t.nav_switches());
    s += " | nav " + t.nav_mode() + nav;
  }
  if (!t.has_nearest_person_m()) {
    s += " | people unknown";
  } else if (t.nearest_person_m() >= 0) {
    std::string pat = v1::HumanPattern_Name(t.pattern());
    for (auto& ch : pat) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    s += " | person " + fmtFixed(t.nearest_person_m(), 1) + " m " + (t.pattern() == v1::PATTERN_NONE ? "?" : pat) +
         " speed x" + known(t.has_speed_factor(), t.speed_factor(), fmtFixed, 2);
  }
  if (t.has_perception()) s += std::string(" | ") + perceptionName(t.perception().mode()) + " " + seenPeople(t.perception());
  if (t.has_wide_perception()) s += " | wide head " + seenPeople(t.wide_perception());
  if (t.ultrasonic_m_size() > 0) {
    s += " | us";
    for (double r : t.ultrasonic_m()) s += r < 0 ? " --" : " " + fmtFixed(r);
  }
  if (t.gas_size() > 0) {
    s += " | gas";
    const auto& ch = snap->hello.gas_channels();
    for (int i = 0; i < t.gas_size(); ++i) {
      const double g = t.gas(i);
      s += " " + (i < ch.size() ? ch[i].name() : "gas" + std::to_string(i)) + " " +
           (std::isnan(g) ? std::string("--") : fmtShort(g, 1));
    }
  }
  if (t.active_alarms_size() > 0) {
    // The worst first: HIGH, then LOW, then sensor faults.
    std::string high, low, fault;
    for (const auto& a : t.active_alarms()) {
      if (a.level() == v1::GasAlarm::SENSOR_FAULT) {
        fault += " " + a.channel_name() + " " + a.fault();
        continue;
      }
      std::string& dst = a.level() == v1::GasAlarm::HIGH ? high : low;
      dst += " " + a.channel_name() + (a.level() == v1::GasAlarm::HIGH ? " HIGH " : " LOW ") +
             (std::isnan(a.value()) ? std::string("--") : fmtShort(a.value(), 1)) + " " + a.unit();
    }
    if (!high.empty() || !low.empty()) s += " | ALARM" + high + low;
    if (!fault.empty()) s += " | SENSOR FAULT" + fault;
  }
  s += " | bat " + known(t.has_battery_v(), t.battery_v(), fmtFixed, 1) + (t.has_battery_v() ? " V" : "");
  s += " | faults " + faultNames(t.faults());
  s += " | tlm " + fmtFixed(snap->telemetry_hz, 0) + " Hz";
  if (snap->connected && snap->telemetry_age_s > 0.5) s += " (stale " + fmtFixed(snap->telemetry_age_s, 1) + " s)";
  s += (t.faults() & v1::FAULT_SERIAL_DOWN) ? " | serial DOWN" : " | serial ok";
  if (snap->connected) s += videoFigures(*snap, video);
  return s;
}

bool statusIsAlarm(const std::optional<RobotSnapshot>& snap) {
  if (!snap || !snap->connected) return true;
  if (!snap->has_telemetry) return false;
  const auto m = snap->telemetry.mode();
  return m == v1::ESTOP || m == v1::FAILSAFE || snap->telemetry.faults() != 0 ||
         snap->telemetry.active_alarms_size() > 0;
}

}  // namespace inspect::server
