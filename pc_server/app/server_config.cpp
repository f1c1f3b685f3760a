#include "pc_server/app/server_config.hpp"

#include <boost/asio/ip/address.hpp>

#include "pc_server/sparkplug/sparkplug_metric.hpp"

namespace inspect::server {

bool validBindAddress(const std::string& address) {
  boost::system::error_code ec;
  (void)boost::asio::ip::make_address(address, ec);
  return !ec;
}

ServerConfig loadServerConfig(const config::ConfigNode& root) {
  ServerConfig c;
  c.bind_address = root.string("bind", c.bind_address);
  if (!validBindAddress(c.bind_address))
    root.fail("bind", "'" + c.bind_address + "' is not a numeric IP address (e.g. 0.0.0.0, 127.0.0.1, ::)");
  c.port = static_cast<uint16_t>(root.integer("port", c.port, 0, 65535));
  c.server_id = root.string("server_id", c.server_id);
  if (c.server_id.empty() || c.server_id.size() > 64) root.fail("server_id", "must be 1 to 64 characters");
  c.heartbeat_period_s = root.number("heartbeat_period_s", c.heartbeat_period_s, 0.01, 5);
  // The robot sends heartbeats at 0.1 s by default; a timeout must cover a few of them.
  c.session_timeout_s = root.number("session_timeout_s", c.session_timeout_s, 0.2, 60);
  c.telemetry_stale_s = root.number("telemetry_stale_s", c.telemetry_stale_s, 0, 60);
  if (c.telemetry_stale_s > 0 && c.telemetry_stale_s < 0.1)
    root.fail("telemetry_stale_s", "must be 0 (off) or at least 0.1 s (robots send telemetry at up to 100 Hz)");
  c.handshake_timeout_s = root.number("handshake_timeout_s", c.handshake_timeout_s, 0.1, 60);
  // The robot zeroes a set-point older than 300 ms; below 10 Hz it would stutter.
  c.teleop_resend_hz = root.number("teleop_resend_hz", c.teleop_resend_hz, 10, 100);
  c.max_frame_bytes = static_cast<std::size_t>(root.integer("max_frame_bytes", static_cast<long>(c.max_frame_bytes),
                                                            1024, 64L * 1024 * 1024));
  const auto lim = root.optChild("robot_limits");
  c.robot_limits.messages_per_s = lim.number("messages_per_s", c.robot_limits.messages_per_s, 10, 1e7);
  c.robot_limits.bytes_per_s = lim.number("bytes_per_s", c.robot_limits.bytes_per_s, 1e3, 1e10);
  c.robot_limits.burst_s = lim.number("burst_s", c.robot_limits.burst_s, 0.05, 60);
  c.robot_limits.close_after_s = lim.number("close_after_s", c.robot_limits.close_after_s, 0.5, 600);
  c.status_refresh_hz = root.number("status_refresh_hz", c.status_refresh_hz, 0.5, 30);
  const auto v = root.optChild("video");
  auto& vc = c.video;
  vc.enabled = v.boolean("enabled", vc.enabled);
  vc.bind = v.string("bind", vc.bind);
  if (!vc.bind.empty() && !validBindAddress(vc.bind)) v.fail("bind", "'" + vc.bind + "' is not a numeric IP address");
  vc.port = static_cast<uint16_t>(v.integer("port", vc.port, 0, 65535));
  vc.dir = v.string("dir", vc.dir);
  if (vc.dir.empty()) v.fail("dir", "must not be empty");
  vc.forward_base_port = static_cast<uint16_t>(v.integer("forward_base_port", vc.forward_base_port, 0, 65000));
  vc.window = v.string("window", vc.window);
  if (vc.window != "auto" && vc.window != "on" && vc.window != "off")
    v.fail("window", "'" + vc.window + "' is not one of auto, on, off");
  vc.snapshot_period_s = v.number("snapshot_period_s", vc.snapshot_period_s, 0, 3600);
  vc.reorder_window = static_cast<std::size_t>(v.integer("reorder_window", static_cast<long>(vc.reorder_window), 1, 1024));
  vc.keyframe_min_interval_s = v.number("keyframe_min_interval_s", vc.keyframe_min_interval_s, 0.05, 10);
  const auto r = root.optChild("recording");
  auto& rc = c.recording;
  rc.enabled = r.boolean("enabled", rc.enabled);
  rc.dir = r.string("dir", rc.dir);
  if (rc.dir.empty()) r.fail("dir", "must not be empty");
  rc.auto_start = r.boolean("auto_start", rc.auto_start);
  rc.compression = r.string("compression", rc.compression);
  if (rc.compression != "zstd" && rc.compression != "none")
    r.fail("compression", "'" + rc.compression + "' is not one of zstd, none");
  rc.max_fragment_s = r.number("max_fragment_s", rc.max_fragment_s, 0.1, 60);
  rc.catalog = r.string("catalog", rc.catalog);
  rc.shared_runs = r.string("shared_runs", rc.shared_runs);
  c.operator_socket = root.string("operator_socket", c.operator_socket);
  c.site_map = root.string("site_map", c.site_map);
  const auto f = root.optChild("foxglove");
  auto& fc = c.foxglove;
  fc.enabled = f.boolean("enabled", fc.enabled);
  fc.bind = f.string("bind", fc.bind);
  if (!validBindAddress(fc.bind)) f.fail("bind", "'" + fc.bind + "' is not a numeric IP address (e.g. 127.0.0.1, 0.0.0.0)");
  fc.port = static_cast<uint16_t>(f.integer("port", fc.port, 0, 65535));
  fc.auth = f.string("auth", fc.auth);
  if (fc.auth != "token" && fc.auth != "none") f.fail("auth", "'" + fc.auth + "' is not one of token, none");
  if (fc.auth == "none" && fc.bind != "127.0.0.1" && fc.bind != "::1")
    f.fail("auth", "none is only allowed with bind 127.0.0.1 or ::1 (other hosts must present the token)");
  fc.token_file = f.string("token_file", fc.token_file);
  if (fc.auth == "token" && fc.token_file.empty()) f.fail("token_file", "must not be empty with auth: token");
  fc.tls = f.boolean("tls", fc.tls);
  fc.allowed_origins = f.strings("allowed_origins");
  fc.scene_hz = f.number("scene_hz", fc.scene_hz, 1, 30);
  fc.grid_hz = f.number("grid_hz", fc.grid_hz, 0.1, 10);
  fc.teleop_timeout_s = f.number("teleop_timeout_s", fc.teleop_timeout_s, 0.1, 2);
  fc.max_clients = static_cast<int>(f.integer("max_clients", fc.max_clients, 1, 256));
  const auto sp = root.optChild("sparkplug");
  auto& sc = c.sparkplug;
  sc.enabled = sp.boolean("enabled", sc.enabled);
  sc.host = sp.string("host", sc.host);
  if (sc.host.empty()) sp.fail("host", "must not be empty (the MQTT broker's name or address)");
  sc.port = static_cast<uint16_t>(sp.integer("port", sc.port, 1, 65535));
  sc.group_id = sp.string("group_id", sc.group_id);
  if (!sparkplug::validId(sc.group_id)) sp.fail("group_id", "'" + sc.group_id + "' must be non-empty without '/', '+' or '#'");
  sc.edge_node_id = sp.string("edge_node_id", sc.edge_node_id);
  if (!sc.edge_node_id.empty() && !sparkplug::validId(sc.edge_node_id))
    sp.fail("edge_node_id", "'" + sc.edge_node_id + "' must be without '/', '+' or '#' (\"\" = the server_id)");
  sc.primary_host_id = sp.string("primary_host_id", sc.primary_host_id);
  if (!sc.primary_host_id.empty() && !sparkplug::validId(sc.primary_host_id))
    sp.fail("primary_host_id", "'" + sc.primary_host_id + "' must be without '/', '+' or '#' (\"\" = none)");
  sc.credentials_file = sp.string("credentials_file", sc.credentials_file);
  sc.ca = sp.string("ca", sc.ca);
  sc.cert = sp.string("cert", sc.cert);
  sc.key = sp.string("key", sc.key);
  if (sc.cert.empty() != sc.key.empty()) sp.fail(sc.cert.empty() ? "cert" : "key", "cert and key go together");
  if (!sc.cert.empty() && sc.ca.empty()) sp.fail("ca", "must be set with a client certificate (TLS)");
  sc.qos = static_cast<int>(sp.integer("qos", sc.qos, 0, 1));
  sc.keepalive_s = sp.number("keepalive_s", sc.keepalive_s, 5, 600);  // libmosquitto refuses 1-4
  sc.min_period_s = sp.number("min_period_s", sc.min_period_s, 0.05, 60);
  sc.commands = sp.boolean("commands", sc.commands);
  sc.spool_file = sp.string("spool_file", sc.spool_file);
  sc.queue_max = static_cast<std::size_t>(sp.integer("queue_max", static_cast<long>(sc.queue_max), 1, 10'000'000));
  const auto db = sp.optChild("deadbands");
  auto& d = sc.deadbands;
  d.position_m = db.number("position_m", d.position_m, 0, 100);
  d.heading_rad = db.number("heading_rad", d.heading_rad, 0, 3.15);
  d.speed_m_s = db.number("speed_m_s", d.speed_m_s, 0, 10);
  d.battery_v = db.number("battery_v", d.battery_v, 0, 100);
  d.person_m = db.number("person_m", d.person_m, 0, 100);
  d.gas_fraction = db.number("gas_fraction", d.gas_fraction, 0, 1);
  const auto t = root.optChild("tls");
  for (const char* key : {"ca", "cert", "key"}) {
    std::string& field = key[0] == 'c' ? (key[1] == 'a' ? c.tls.ca : c.tls.cert) : c.tls.key;
    field = t.string(key, field);
    if (field.empty()) t.fail(key, "must not be empty (plaintext is only the --plaintext flag)");
  }
  return c;
}

ServerConfig loadServerConfigFile(const std::string& path) {
  const auto root = config::ConfigNode::loadFile(path);
  ServerConfig c = loadServerConfig(root);
  root.checkKnown();
  return c;
}

}  // namespace inspect::server
