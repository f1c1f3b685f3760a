#include "robot_client/client_config.hpp"

#include "shared/net/robot_id.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>

namespace inspect::client {

bool validRobotId(const std::string& id) { return net::validRobotId(id); }

bool showsPeople(const std::string& source) { return source != "synthetic"; }

std::string wideSourceProblem(const std::string& source) {
  return source.empty() || showsPeople(source) ? ""
                                               : "the synthetic picture shows nobody: a camera, a file or sim:PATH";
}

namespace {
// A head's detection settings (perception: the PTZ head; wide_head).
void readDetection(const config::ConfigNode& n, DetectionParams& d) {
  d.detector = n.oneOf("detector", d.detector, {"hog", "hog-daimler", "haar-fullbody", "haar-upperbody"});
  d.width = static_cast<int>(n.integer("width", d.width, 64, 4096));
  d.height = static_cast<int>(n.integer("height", d.height, 64, 4096));
  d.rate_hz = n.number("rate_hz", d.rate_hz, 0.1, 30);
  d.max_core_share = n.number("max_core_share", d.max_core_share, 0.05, 1.0);
  d.hit_threshold = n.number("hit_threshold", d.hit_threshold, -1.0, 3.0);
  d.group_threshold = static_cast<int>(n.integer("group_threshold", d.group_threshold, 0, 20));
  d.floor_band = n.boolean("floor_band", d.floor_band);
}

std::string readPixelFormat(const config::ConfigNode& n, const std::string& dflt) {
  std::string f = n.string("pixel_format", dflt);
  if (!f.empty() && f.size() != 4) n.fail("pixel_format", "a FOURCC is 4 characters, e.g. MJPG");
  return f;
}
}  // namespace

ClientConfig loadClientConfig(const config::ConfigNode& root) {
  ClientConfig c;
  c.robot_id = root.string("robot_id", c.robot_id);
  if (!validRobotId(c.robot_id)) root.fail("robot_id", "'" + c.robot_id + "' must be 1-64 characters of A-Z a-z 0-9 _ -");
  c.realtime_priority = static_cast<int>(root.integer("realtime_priority", c.realtime_priority, 0, 99));
  const auto s = root.optChild("server");
  c.server_host = s.string("host", c.server_host);
  if (c.server_host.empty()) s.fail("host", "must not be empty");
  c.server_port = static_cast<int>(s.integer("port", c.server_port, 1, 65535));
  c.reconnect_min_s = s.number("reconnect_min_s", c.reconnect_min_s, 0.01, 60);
  c.reconnect_max_s = s.number("reconnect_max_s", c.reconnect_max_s, c.reconnect_min_s, 600);
  c.handshake_timeout_s = s.number("handshake_timeout_s", c.handshake_timeout_s, 0.1, 60);
  c.server_heartbeat_period_s = s.number("heartbeat_period_s", c.server_heartbeat_period_s, 0.01, 5);
  c.telemetry_hz = s.number("telemetry_hz", c.telemetry_hz, 1, 100);
  const auto t = root.optChild("tls");
  c.tls.ca = t.string("ca", c.tls.ca);
  if (c.tls.ca.empty()) t.fail("ca", "must not be empty (plaintext is only the --plaintext flag)");
  c.tls.cert = t.string("cert", c.tls.cert);
  c.tls.key = t.string("key", c.tls.key);
  c.tls.server_name = t.string("server_name", c.tls.server_name);
  const auto ser = root.optChild("serial");
  c.serial_device = ser.string("device", c.serial_device);
  c.baud = static_cast<int>(ser.integer("baud", c.baud, 1200, 4000000));
  static constexpr int kRates[] = {9600, 19200, 38400, 57600, 115200, 230400, 460800, 921600};
  if (std::find(std::begin(kRates), std::end(kRates), c.baud) == std::end(kRates))
    ser.fail("baud", std::to_string(c.baud) + " is not a standard rate (9600 ... 921600)");
  c.serial_reopen_period_s = ser.number("reopen_period_s", c.serial_reopen_period_s, 0.1, 60);
  c.mcu_heartbeat_period_s = ser.number("heartbeat_period_s", c.mcu_heartbeat_period_s, 0.01, 0.4);
  const auto sa = root.optChild("safety");
  c.safety.link_timeout_s = sa.number("link_timeout_s", c.safety.link_timeout_s, 0.05, 10);
  c.safety.command_timeout_s = sa.number("command_timeout_s", c.safety.command_timeout_s, 0.05, 10);
  c.safety.sensor_timeout_s = sa.number("sensor_timeout_s", c.safety.sensor_timeout_s, 0.02, 5);
  c.safety.obstacle_stop_m = sa.number("obstacle_stop_m", c.safety.obstacle_stop_m, 0, 5);
  c.safety.obstacle_slow_m = sa.number("obstacle_slow_m", c.safety.obstacle_slow_m, 0, 10);
  c.safety.nav_stall_s = sa.number("nav_stall_s", c.safety.nav_stall_s, 1, 3600);
  c.safety.gas_reaction = *robot::gasReactionOf(
      sa.oneOf("gas_reaction", robot::gasReactionName(c.safety.gas_reaction), {"continue", "stop", "retreat"}));
  if (c.safety.obstacle_slow_m <= c.safety.obstacle_stop_m && c.safety.obstacle_slow_m > 0)
    sa.fail("obstacle_slow_m", "must be above obstacle_stop_m (or 0 to turn the obstacle stop off)");
  const auto ev = root.optChild("events");
  c.events.journal = ev.string("journal", c.events.journal);
  c.events.max_pending = static_cast<int>(ev.integer("max_pending", c.events.max_pending, 16, 1000000));
  c.events.sync_period_s = ev.number("sync_period_s", c.events.sync_period_s, 0, 10);
  c.map_file = root.string("map", c.map_file);
  const auto v = root.optChild("video");
  auto& vp = c.video;
  vp.enabled = v.boolean("enabled", vp.enabled);
  vp.source = v.string("source", vp.source);
  if (vp.source.empty()) v.fail("source", "must not be empty (\"synthetic\", \"v4l2:/dev/videoN\", \"file:PATH\" or \"sim:PATH\")");
  vp.width = static_cast<int>(v.integer("width", vp.width, 64, 4096));
  vp.height = static_cast<int>(v.integer("height", vp.height, 64, 4096));
  if (vp.width % 2 || vp.height % 2) v.fail("width", "width and height must be even (4:2:0 video)");
  vp.fps = v.number("fps", vp.fps, 1, 120);
  vp.pixel_format = readPixelFormat(v, vp.pixel_format);
  vp.encoder = v.string("encoder", vp.encoder);
  if (vp.encoder != "libx264" && vp.encoder != "h264_v4l2m2m" && vp.encoder != "auto")
    v.fail("encoder", "'" + vp.encoder + "' is not one of libx264, h264_v4l2m2m, auto");
  vp.preset = v.string("preset", vp.preset);
  if (vp.preset != "ultrafast" && vp.preset != "superfast" && vp.preset != "veryfast")
    v.fail("preset", "'" + vp.preset + "' is not one of ultrafast, superfast, veryfast");
  vp.bitrate_kbps = static_cast<int>(v.integer("bitrate_kbps", vp.bitrate_kbps, 50, 50000));
  vp.gop = static_cast<int>(v.integer("gop", vp.gop, 1, 600));
  vp.intra_refresh = v.boolean("intra_refresh", vp.intra_refresh);
  vp.host = v.string("host", vp.host);
  vp.port = static_cast<int>(v.integer("port", vp.port, 1, 65535));
  vp.mtu = static_cast<int>(v.integer("mtu", vp.mtu, 256, 9000));
  vp.retransmission = v.boolean("retransmission", vp.retransmission);
  vp.history_packets = static_cast<int>(v.integer("history_packets", vp.history_packets, 0, 65536));
  vp.history_s = v.number("history_s", vp.history_s, 0.01, 10);
  const auto ad = v.optChild("adapt");
  vp.adapt = ad.boolean("enabled", vp.adapt);
  vp.adapt_min_kbps = static_cast<int>(ad.integer("min_kbps", vp.adapt_min_kbps, 50, 50000));
  vp.adapt_max_kbps = static_cast<int>(ad.integer("max_kbps", vp.adapt_max_kbps, 0, 50000));
  if (vp.adapt_max_kbps != 0 && vp.adapt_max_kbps < vp.adapt_min_kbps)
    ad.fail("max_kbps", std::to_string(vp.adapt_max_kbps) + " is below min_kbps " + std::to_string(vp.adapt_min_kbps));
  const auto pe = root.optChild("perception");
  auto& pp = c.perception;
  pp.enabled = pe.boolean("enabled", pp.enabled);
  readDetection(pe, pp);
  pp.stale_s = pe.number("stale_s", pp.stale_s, 0.1, 10);
  pp.ahead_deg = pe.number("ahead_deg", pp.ahead_deg, 1, 90);
  pp.look_ahead = pe.boolean("look_ahead", pp.look_ahead);
  pp.look_ahead_within_m = pe.number("look_ahead_within_m", pp.look_ahead_within_m, 0.5, 20);
  pp.look_ahead_hold_s = pe.number("look_ahead_hold_s", pp.look_ahead_hold_s, 0, 60);
  const auto wh = root.optChild("wide_head");
  auto& wp = c.wide_head;
  wp.source = wh.string("source", wp.source);
  if (const auto why = wideSourceProblem(wp.source); !why.empty()) wh.fail("source", why + ", or \"\" for none");
  readDetection(wh, wp);
  if (wp.width % 2 || wp.height % 2) wh.fail("width", "width and height must be even");
  wp.fps = wh.number("fps", wp.fps, 1, 120);
  wp.pixel_format = readPixelFormat(wh, wp.pixel_format);
  wp.stream = wh.boolean("stream", wp.stream);
  wp.bitrate_kbps = static_cast<int>(wh.integer("bitrate_kbps", wp.bitrate_kbps, 50, 50000));
  return c;
}

ClientConfig loadClientConfigFile(const std::string& path) {
  const auto root = config::ConfigNode::loadFile(path);
  ClientConfig c = loadClientConfig(root);
  root.checkKnown();
  // A relative map path is taken from the working directory, or else from the
  // directory above the config file's (config/client.yaml names config/worlds/...).
  struct stat st {};
  if (!c.map_file.empty() && c.map_file.front() != '/' && ::stat(c.map_file.c_str(), &st) != 0) {
    const auto slash = path.rfind('/');
    const std::string alt = (slash == std::string::npos ? std::string(".") : path.substr(0, slash)) + "/../" + c.map_file;
    if (::stat(alt.c_str(), &st) == 0) c.map_file = alt;
  }
  return c;
}

}  // namespace inspect::client
