// robot_client: the Raspberry Pi process. Bridges the MCU serial line, runs the
// 100 Hz control loop and keeps the link to pc_server.
#include <sys/stat.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>

#include "robot_client/client_config.hpp"
#include "robot_client/robot_app.hpp"
#include "shared/world/robot_map.hpp"
#include "shared/behavior/human_awareness.hpp"
#include "shared/robot/awareness.hpp"
#include "shared/config/control_config.hpp"
#include "shared/fuzzy/fis_error.hpp"
#include "shared/config/config_node.hpp"
#include "shared/net/tls.hpp"
#include "shared/util/cli_args.hpp"
#include "shared/util/log.hpp"
#include "shared/util/realtime.hpp"
#include "shared/world/world.hpp"

namespace {

constexpr const char* kUsage = R"(usage: robot_client [options]

Runs on the robot's Raspberry Pi: talks to the MCU over serial, runs the
100 Hz control loop, and keeps a TCP link to pc_server.

options:
  --config FILE        client settings (default: config/client.yaml if present)
  --robot-config FILE  robot geometry and limits (default: config/robot.yaml if present)
  --control-config FILE  tracking controllers (default: config/control.yaml if present)
  --behavior-config FILE human awareness: people tracking, patterns, Eq 9 speed
                       strategy (default: config/behavior.yaml if present; else off)
  --serial PATH        serial device of the MCU (overrides serial.device),
                       e.g. /dev/serial0, or the pty printed by mcu_sim
  --server HOST:PORT   pc_server address (overrides server.host/port)
  --id ROBOT_ID        robot id (overrides robot_id)
  --map FILE           world file (config/worlds/*.yaml) whose walls and obstacles,
                       moved into the odometry frame (origin = the world's start
                       pose), people tracking treats as static (overrides
                       map: in the client config)
  --gas-reaction R     reaction to a gas HIGH alarm on a route: continue, stop
                       (hold until resume) or retreat (overrides safety.gas_reaction)
  --certs DIR          TLS files DIR/ca.pem, DIR/<robot id>.pem, DIR/<robot id>.key
                       (overrides tls.*; default certs; scripts/make_certs.sh makes them)
  --plaintext          no TLS: the link is neither encrypted nor authenticated
                       (isolated test benches only; the server needs --plaintext too)
  --journal FILE       the event journal (store-and-forward; overrides events.journal;
                       "" = memory only)
  --cmd-log FILE       write every wheel command sent to the MCU (CSV; for tests)
  --realtime-priority N  SCHED_FIFO priority of the control loop once started,
                       N in [0, 99], 0 = normal (overrides realtime_priority;
                       needs root, CAP_SYS_NICE or LimitRTPRIO, else a warning)
  --video-source URI   camera stream source (overrides video.source): synthetic,
                       v4l2:/dev/videoN, file:PATH or sim:PATH (the simulated
                       camera of mcu_sim --camera PATH)
  --video-port PORT    UDP port of the server's video receiver (overrides video.port)
  --wide-video-source URI  the wide, fixed head's pictures, detected on the robot
                       (overrides wide_head.source; needs wide_camera in the robot
                       config): v4l2:/dev/videoN, file:PATH or sim:PATH (mcu_sim --wide-camera PATH)
  --wide-stream        stream the wide head's pictures too (wide_head.stream: true)
  --no-video           do not stream video, neither head (overrides video.enabled and
                       wide_head.stream; the heads' people detection goes on)
  --version            print the version and exit
  --help               print this help and exit

SIGUSR1 logs the control loop's figures so far (sensor frame in -> wheel command out)
and counts them anew; they are logged at the end too.

exit status: 0 after SIGINT/SIGTERM, 2 on a bad option or configuration.
)";

bool fileExists(const char* p) {
  struct stat st {};
  return ::stat(p, &st) == 0;
}

[[noreturn]] void usageError(const std::string& msg) {
  std::fprintf(stderr, "robot_client: %s\n", msg.c_str());
  std::exit(2);
}

/// The command line's choices (kUsage); unset ones leave the config files' values.
struct CliArgs {
  std::string config_path, robot_path, control_path, behavior_path;
  std::string serial_dev, server, id, cmd_log, map_path, video_source, wide_video_source, certs_dir;
  std::optional<int> video_port, realtime_priority;
  std::optional<std::string> journal;
  std::optional<inspect::robot::GasReaction> gas_reaction;
  bool no_video = false, plaintext = false, wide_stream = false;
};

/// Reads the command line (--help and --version print and exit 0; a usage error exits 2).
CliArgs parseArgs(int argc, char** argv) {
  using namespace inspect;
  CliArgs o;
  o.config_path = fileExists("config/client.yaml") ? "config/client.yaml" : "";
  o.robot_path = fileExists("config/robot.yaml") ? "config/robot.yaml" : "";
  o.control_path = fileExists("config/control.yaml") ? "config/control.yaml" : "";
  o.behavior_path = fileExists("config/behavior.yaml") ? "config/behavior.yaml" : "";
  try {
    cli::ArgReader a(argc, argv);
    while (a.next()) {
      if (a.isHelp()) {
        std::fputs(kUsage, stdout);
        std::exit(0);
      } else if (a.is("--version")) {
        std::printf("robot_client %s\n", INSPECT_VERSION);
        std::exit(0);
      } else if (a.is("--config")) o.config_path = a.text();  // "": built-in defaults
      else if (a.is("--robot-config")) o.robot_path = a.text();
      else if (a.is("--control-config")) o.control_path = a.text();
      else if (a.is("--behavior-config")) o.behavior_path = a.text();  // "": people awareness off
      else if (a.is("--serial")) o.serial_dev = a.path();
      else if (a.is("--server")) o.server = a.path();
      else if (a.is("--id")) o.id = a.path();
      else if (a.is("--cmd-log")) o.cmd_log = a.path();
      else if (a.is("--journal")) o.journal = a.text();
      else if (a.is("--map")) o.map_path = a.path();
      else if (a.is("--video-source")) o.video_source = a.path();
      else if (a.is("--wide-video-source")) o.wide_video_source = a.path();
      else if (a.is("--video-port")) o.video_port = static_cast<int>(a.integer(1, 65535));
      else if (a.is("--certs")) o.certs_dir = a.path();
      else if (a.is("--realtime-priority")) o.realtime_priority = static_cast<int>(a.integer(0, 99));
      else if (a.is("--plaintext")) o.plaintext = true;
      else if (a.is("--no-video")) o.no_video = true;
      else if (a.is("--wide-stream")) o.wide_stream = true;
      else if (a.is("--gas-reaction")) o.gas_reaction = robot::gasReactionOf(a.choice({"continue", "stop", "retreat"}));
      else a.unknown();
    }
    if (!o.id.empty() && !client::validRobotId(o.id))
      throw cli::UsageError("--id: '" + o.id + "' must be 1-64 characters of A-Z a-z 0-9 _ -");
    if (o.plaintext && !o.certs_dir.empty()) throw cli::UsageError("--plaintext cannot be combined with --certs");
  } catch (const cli::UsageError& e) {
    usageError(e.what());
  }
  return o;
}

/// The command line over the client config: ids, server, TLS files, video, priority.
void applyArgs(const CliArgs& o, inspect::client::ClientConfig& cfg) {
  using namespace inspect;
  if (!o.serial_dev.empty()) cfg.serial_device = o.serial_dev;
  if (!o.map_path.empty()) cfg.map_file = o.map_path;
  if (o.journal) cfg.events.journal = *o.journal;
  if (o.gas_reaction) cfg.safety.gas_reaction = *o.gas_reaction;
  if (!o.id.empty()) cfg.robot_id = o.id;
  if (!o.server.empty()) {
    const auto colon = o.server.rfind(':');
    if (colon == std::string::npos || colon == 0) usageError("--server: '" + o.server + "' is not HOST:PORT");
    cfg.server_host = o.server.substr(0, colon);
    char* end = nullptr;
    const long port = std::strtol(o.server.c_str() + colon + 1, &end, 10);
    if (*end != '\0' || port < 1 || port > 65535) usageError("--server: '" + o.server + "' has no port number (1-65535)");
    cfg.server_port = static_cast<int>(port);
  }
  if (!o.certs_dir.empty()) {
    cfg.tls.ca = o.certs_dir + "/ca.pem";
    cfg.tls.cert = o.certs_dir + "/" + cfg.robot_id + ".pem";
    cfg.tls.key = o.certs_dir + "/" + cfg.robot_id + ".key";
  }
  // Unset: the robot's files beside the CA's (certs/ by default,
  // /etc/inspect/certs in the package).
  const auto ca_dir = std::filesystem::path(cfg.tls.ca).parent_path();
  if (cfg.tls.cert.empty()) cfg.tls.cert = (ca_dir / (cfg.robot_id + ".pem")).string();
  if (cfg.tls.key.empty()) cfg.tls.key = (ca_dir / (cfg.robot_id + ".key")).string();
  if (cfg.tls.server_name.empty()) cfg.tls.server_name = cfg.server_host;
  cfg.tls.plaintext = o.plaintext;
  if (o.plaintext) {
    std::fprintf(stderr, "robot_client: %s\n", net::kPlaintextWarning);
    log::warn("main", net::kPlaintextWarning);
  }
  if (!o.video_source.empty()) cfg.video.source = o.video_source;
  if (!o.wide_video_source.empty()) {
    if (const auto why = client::wideSourceProblem(o.wide_video_source); !why.empty())
      throw config::ConfigError("--wide-video-source: " + why);
    cfg.wide_head.source = o.wide_video_source;
  }
  if (o.wide_stream) cfg.wide_head.stream = true;
  if (o.no_video) cfg.video.enabled = cfg.wide_head.stream = false;
  if (o.video_port) cfg.video.port = *o.video_port;
  if (o.realtime_priority) cfg.realtime_priority = *o.realtime_priority;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace inspect;
  const CliArgs args = parseArgs(argc, argv);
  const std::string& control_path = args.control_path;
  const std::string& behavior_path = args.behavior_path;
  const std::string& cmd_log = args.cmd_log;
  try {
    client::ClientConfig cfg;
    if (!args.config_path.empty()) cfg = client::loadClientConfigFile(args.config_path);
    config::RobotConfig robot;
    if (!args.robot_path.empty()) robot = config::loadRobotConfigFile(args.robot_path);
    applyArgs(args, cfg);

    config::ControlConfig control;
    if (!control_path.empty()) control = config::loadControlConfigFile(control_path);
    config::applyRobot(control, robot);
    const auto scheduler = config::loadScheduler(control);

    std::vector<geometry::Segment> map;
    if (!cfg.map_file.empty()) {
      map = world::mapFromWorld(world::loadWorldFile(cfg.map_file));
      log::info("main", "map ", cfg.map_file, ": ", map.size(), " wall segments");
    }
    std::unique_ptr<behavior::HumanAwareness> awareness;
    if (!behavior_path.empty()) {
      awareness = robot::makeAwareness(robot, behavior::loadAwarenessConfigFile(behavior_path), std::move(map),
                                       behavior_path);
    } else {
      log::warn("main", "no behaviour config: people are not tracked and do not slow the robot",
                map.empty() ? "" : " (the map is not used)");
    }

    boost::asio::io_context io(1);
    client::RobotApp app(io, cfg, robot, control, scheduler, cmd_log);
    app.setAwareness(std::move(awareness));
    boost::asio::signal_set signals(io, SIGINT, SIGTERM);
    signals.async_wait([&](const boost::system::error_code&, int sig) {
      log::info("main", "signal ", sig, ": stopping");
      app.stop();
      // Let the final zero command reach the serial line, then leave.
      io.poll();
      io.stop();
    });
    // SIGUSR1: the loop's figures so far in the log, then counted anew
    // (bench_loop's measurement window; `kill -USR1` on a robot).
    boost::asio::signal_set usr1(io, SIGUSR1);
    std::function<void()> wait_usr1 = [&] {
      usr1.async_wait([&](const boost::system::error_code& ec, int) {
        if (ec) return;
        app.logLoopFigures();
        wait_usr1();
      });
    };
    wait_usr1();
    log::info("main", "robot_client ", INSPECT_VERSION, " id=", cfg.robot_id, " serial=", cfg.serial_device,
              " server=", cfg.server_host, ":", cfg.server_port);
    app.start();
    // The loop real-time only now that start-up (libraries, lookup tables,
    // the encoder) is done: a process starting at SCHED_FIFO holds a core
    // for ~300 ms from every other loop on the machine (issue 36).
    if (const std::string why = util::enterRealtime(cfg.realtime_priority); !why.empty())
      log::warn("main", "control loop at normal priority: ", why);
    else if (cfg.realtime_priority > 0)
      log::info("main", "control loop SCHED_FIFO priority ", cfg.realtime_priority);
    io.run();
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "robot_client: %s\n", e.what());
    return 2;
  } catch (const net::TlsError& e) {
    std::fprintf(stderr, "robot_client: TLS: %s (or --plaintext for an isolated test bench)\n", e.what());
    return 2;
  }
  return 0;
}
