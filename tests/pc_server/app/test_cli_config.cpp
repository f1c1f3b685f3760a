// Command line and config/server.yaml: defaults, overrides, errors that name the flag or key.
#include <gtest/gtest.h>

#include <unistd.h>

#include "pc_server/app/cli_options.hpp"
#include "pc_server/app/server_app.hpp"
#include "pc_server/app/server_config.hpp"
#include "tests/support/paths.hpp"

using namespace inspect;
using namespace inspect::server;

namespace {
std::string cliError(const std::vector<std::string>& args) {
  try {
    (void)parseCli(args);
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

std::string configError(const std::string& yaml) {
  try {
    const auto root = config::ConfigNode::loadString(yaml, "server.yaml");
    (void)loadServerConfig(root);
    root.checkKnown();
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(Cli, FlagsAndValues) {
  const auto o = parseCli({"--config", "a.yaml", "--bind=127.0.0.1", "--port", "0", "--port-file", "p", "--script",
                           "s.txt", "--interactive"});
  EXPECT_EQ(o.config_path, "a.yaml");
  EXPECT_EQ(o.bind_address, "127.0.0.1");
  EXPECT_EQ(o.port, 0);
  EXPECT_EQ(o.port_file, "p");
  EXPECT_EQ(o.script_path, "s.txt");
  EXPECT_TRUE(o.interactive);
  EXPECT_FALSE(o.no_console);
  EXPECT_TRUE(parseCli({"--help"}).help);
  EXPECT_FALSE(parseCli({}).port.has_value());
}

TEST(Cli, VideoFlags) {
  const auto o = parseCli({"--video-port", "0", "--video-port-file", "vp", "--video-dir", "/tmp/v", "--no-video"});
  EXPECT_EQ(o.video_port, 0);
  EXPECT_EQ(o.video_port_file, "vp");
  EXPECT_EQ(o.video_dir, "/tmp/v");
  EXPECT_TRUE(o.no_video);
  EXPECT_EQ(cliError({"--video-port", "x"}), "--video-port: 'x' is not a port number (0-65535)");
}

TEST(ServerConfig, Video) {
  const auto c = loadServerConfigFile(inspect::test::srcPath("config/server.yaml"));
  const VideoServerConfig d;
  EXPECT_EQ(c.video.enabled, d.enabled);
  EXPECT_EQ(c.video.port, 5600);
  EXPECT_EQ(c.video.forward_base_port, 5700);
  EXPECT_EQ(c.video.dir, "video");
  EXPECT_EQ(c.video.window, "auto");
  EXPECT_DOUBLE_EQ(c.video.keyframe_min_interval_s, 0.3);
  EXPECT_EQ(configError("video:\n  window: maybe\n"), "server.yaml: video.window: 'maybe' is not one of auto, on, off");
  EXPECT_EQ(configError("video:\n  port: 70000\n"), "server.yaml: video.port: 70000 is out of range [0, 65535]");
  EXPECT_EQ(configError("video:\n  bind: here\n"), "server.yaml: video.bind: 'here' is not a numeric IP address");
  EXPECT_EQ(configError("video:\n  keyframe_min_interval_s: 0\n"),
            "server.yaml: video.keyframe_min_interval_s: 0 is out of range [0.05, 10]");
}

TEST(Cli, ErrorsNameTheFlag) {
  EXPECT_EQ(cliError({"--prot", "1"}), "--prot: unknown option (see --help)");
  EXPECT_EQ(cliError({"--port", "70000"}), "--port: '70000' is not a port number (0-65535)");
  EXPECT_EQ(cliError({"--port", "12ab"}), "--port: '12ab' is not a port number (0-65535)");
  EXPECT_EQ(cliError({"--port"}), "--port: missing value");
  EXPECT_EQ(cliError({"--bind", "localhost"}), "--bind: 'localhost' is not a numeric IP address");
  EXPECT_EQ(cliError({"--no-console=1"}), "--no-console: takes no value");
  EXPECT_EQ(cliError({"stray"}), "unexpected argument 'stray'");
  EXPECT_EQ(cliError({"--runs-dir="}), "--runs-dir: empty value");
  EXPECT_EQ(cliError({"--catalog", "postgresql://ops:s3cret@db/fleet"}),
            "--catalog: the URL carries a password, which ps shows to every user; put it in ~/.pgpass, PGPASSFILE "
            "or PGPASSWORD, or in recording.catalog of the config file");
  EXPECT_EQ(parseCli({"--attach=/tmp/op.sock"}).attach, "/tmp/op.sock");
  EXPECT_NE(cliError({"--attach", "/tmp/op.sock", "--plaintext"}).find("takes no other flags"), std::string::npos);
  EXPECT_NE(cliError({"--no-console", "--script", "x"}).find("cannot be combined"), std::string::npos);
}

TEST(Cli, UsageMentionsEveryFlag) {
  const auto u = usageText();
  for (const char* f : {"--config", "--bind", "--port", "--port-file", "--script", "--interactive", "--no-console",
                        "--video-port", "--video-port-file", "--video-dir", "--no-video", "--help"})
    EXPECT_NE(u.find(f), std::string::npos) << f;
}

TEST(ServerConfig, EmptyFileGivesDefaults) {
  const auto c = loadServerConfig(config::ConfigNode::loadString("", "server.yaml"));
  EXPECT_EQ(c.bind_address, "0.0.0.0");
  EXPECT_EQ(c.port, 7600);
  EXPECT_DOUBLE_EQ(c.heartbeat_period_s, 0.05);
  EXPECT_DOUBLE_EQ(c.telemetry_stale_s, 0.25);
  EXPECT_EQ(c.operator_socket, "");
  EXPECT_DOUBLE_EQ(c.session_timeout_s, 1.0);
  EXPECT_DOUBLE_EQ(c.handshake_timeout_s, 5.0);
  EXPECT_DOUBLE_EQ(c.teleop_resend_hz, 20.0);
  EXPECT_EQ(c.max_frame_bytes, 1u << 20);
  EXPECT_DOUBLE_EQ(c.status_refresh_hz, 5.0);
}

TEST(ServerConfig, ShippedFileLoadsWithDefaults) {
  const auto c = loadServerConfigFile(inspect::test::srcPath("config/server.yaml"));
  const ServerConfig d;
  EXPECT_EQ(c.bind_address, d.bind_address);
  EXPECT_EQ(c.port, d.port);
  EXPECT_EQ(c.server_id, d.server_id);
  EXPECT_DOUBLE_EQ(c.heartbeat_period_s, d.heartbeat_period_s);
  EXPECT_DOUBLE_EQ(c.session_timeout_s, d.session_timeout_s);
  EXPECT_DOUBLE_EQ(c.handshake_timeout_s, d.handshake_timeout_s);
  EXPECT_DOUBLE_EQ(c.teleop_resend_hz, d.teleop_resend_hz);
  EXPECT_EQ(c.max_frame_bytes, d.max_frame_bytes);
  EXPECT_DOUBLE_EQ(c.status_refresh_hz, d.status_refresh_hz);
}

TEST(ServerConfig, BadValuesNameFileAndKey) {
  EXPECT_EQ(configError("port: 70000\n"), "server.yaml: port: 70000 is out of range [0, 65535]");
  EXPECT_EQ(configError("teleop_resend_hz: 5\n"), "server.yaml: teleop_resend_hz: 5 is out of range [10, 100]");
  EXPECT_EQ(configError("bind: nowhere\n").rfind("server.yaml: bind: 'nowhere' is not a numeric IP address", 0), 0u);
  EXPECT_EQ(configError("session_timeout_s: fast\n"), "server.yaml: session_timeout_s: 'fast' is not a number");
  EXPECT_EQ(configError("max_frame_bytes: 2048.5\n"), "server.yaml: max_frame_bytes: 2048.5 is not a whole number");
  EXPECT_EQ(configError("max_frame_bytes: 100\n").rfind("server.yaml: max_frame_bytes: 100 is out of range", 0), 0u);
  EXPECT_EQ(configError("heartbeat_period: 0.1\n"),
            "server.yaml: heartbeat_period: unknown key (misspelt, or not used by this program)");
  EXPECT_EQ(configError("server_id: ''\n"), "server.yaml: server_id: must be 1 to 64 characters");
}

TEST(Cli, TheCatalogIdIsTheServersNameOnlyInASharedCatalog) {
  ServerConfig c;
  EXPECT_EQ(catalogServerId(c), "");  // a SQLite file: one server's
  c.server_id = "ops-a";
  EXPECT_EQ(catalogServerId(c), "");
  c.recording.catalog = "postgresql://fleet@db/inspect";
  EXPECT_EQ(catalogServerId(c), "ops-a");
  c.server_id = LinkConfig{}.server_id;  // the default every server would share: the host's name instead
  char host[256] = {};
  ASSERT_EQ(::gethostname(host, sizeof host - 1), 0);
  EXPECT_EQ(catalogServerId(c), host);
  EXPECT_EQ(cliError({"--server-id", std::string(65, 'x')}), "--server-id: must be 1 to 64 characters (as server_id)");
}

TEST(ServerConfig, SparkplugSettingsAreCheckedAndTheBrokerFlagTurnsItOn) {
  // docs/sparkplug.md "Configuration": off by default, every key checked and named.
  EXPECT_FALSE(loadServerConfigFile(inspect::test::srcPath("config/server.yaml")).sparkplug.enabled);
  EXPECT_EQ(configError("sparkplug:\n  group_id: a/b\n"),
            "server.yaml: sparkplug.group_id: 'a/b' must be non-empty without '/', '+' or '#'");
  EXPECT_EQ(configError("sparkplug:\n  edge_node_id: 'x#'\n").find("server.yaml: sparkplug.edge_node_id:"), 0u);
  EXPECT_EQ(configError("sparkplug:\n  qos: 2\n"), "server.yaml: sparkplug.qos: 2 is out of range [0, 1]");
  EXPECT_EQ(configError("sparkplug:\n  cert: c.pem\n"), "server.yaml: sparkplug.key: cert and key go together");
  EXPECT_EQ(configError("sparkplug:\n  cert: c.pem\n  key: k.pem\n"),
            "server.yaml: sparkplug.ca: must be set with a client certificate (TLS)");
  EXPECT_EQ(configError("sparkplug:\n  password: x\n"),
            "server.yaml: sparkplug.password: unknown key (misspelt, or not used by this program)")
      << "a password goes in credentials_file, never in server.yaml";
  EXPECT_EQ(configError("sparkplug:\n  deadbands:\n    gas_fraction: 2\n"),
            "server.yaml: sparkplug.deadbands.gas_fraction: 2 is out of range [0, 1]");
  EXPECT_EQ(parseCli({"--sparkplug-broker", "10.0.0.5:8883"}).sparkplug_broker, "10.0.0.5:8883");
  for (const char* bad : {"broker", "broker:", ":1883", "broker:99999", "broker:18x3"})
    EXPECT_NE(cliError({"--sparkplug-broker", bad}).find("is not HOST:PORT"), std::string::npos) << bad;
  EXPECT_NE(usageText().find("--sparkplug-broker"), std::string::npos);
}
