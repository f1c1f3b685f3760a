#include "pc_server/app/server_app.hpp"

#include <pwd.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <functional>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/signal_set.hpp>

#include "pc_server/console/console.hpp"
#include "pc_server/foxglove/foxglove_bridge.hpp"
#include "pc_server/foxglove/token_file.hpp"
#include "pc_server/scene/site_maps.hpp"
#include "pc_server/sparkplug/sparkplug_credentials.hpp"
#include "pc_server/sparkplug/sparkplug_service.hpp"
#include "shared/config/robot_config.hpp"
#include "pc_server/app/console_runner.hpp"
#include "pc_server/link/link_server.hpp"
#include "pc_server/terminal/operator_socket.hpp"
#include "pc_server/link/robot_registry.hpp"
#include "pc_server/link/session_threads.hpp"
#include "shared/catalog/sql_backend.hpp"
#include "shared/util/startup_error.hpp"
#include "pc_server/operator/stop_flag.hpp"
#include "pc_server/recording/fleet_presence.hpp"
#include "pc_server/recording/recorder.hpp"
#include "pc_server/video/video_hub.hpp"
#include "pc_server/video/video_streams.hpp"
#include "pc_server/video/video_stats_proto.hpp"
#include "shared/util/clock.hpp"
#include "shared/util/file_util.hpp"
#include "shared/util/log.hpp"

namespace inspect::server {

namespace asio = boost::asio;

namespace {
constexpr const char* kDefaultConfig = "config/server.yaml";
constexpr int kIoThreads = 2;
// The console thread checks in every 20-50 ms; a stall this long means it hangs.
constexpr std::chrono::milliseconds kConsoleWatchdog{300};

enum class ConsoleMode { kNone, kScript, kInteractive, kStream };

/// The io_context's threads and the robot sessions' threads; stopped and
/// joined on every way out of runServer(), before what their handlers call.
struct IoThreads {
  asio::io_context& ioc;
  SessionThreads& sessions;
  std::vector<std::thread> threads;
  ~IoThreads() {
    sessions.stop();
    ioc.stop();
    for (auto& t : threads)
      if (t.joinable()) t.join();
  }
};
}  // namespace

static std::string localUserName() {
  if (const char* u = std::getenv("USER"); u && *u) return u;
  if (const passwd* pw = ::getpwuid(::getuid())) return pw->pw_name;
  return "operator";
}

static std::string hostName() {
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0) return "";
  return host;
}

std::string catalogServerId(const ServerConfig& c) {
  if (!catalog::isPostgresUrl(c.recording.catalog)) return "";  // one server's file
  if (c.server_id != LinkConfig{}.server_id) return c.server_id;
  // The default name: every server would share it, so the host's name instead.
  const std::string host = hostName();
  return host.empty() ? c.server_id : host;
}

ServerConfig resolveConfig(const CliOptions& options) {
  ServerConfig c;
  if (options.config_path) {
    c = loadServerConfigFile(*options.config_path);
  } else if (std::filesystem::exists(kDefaultConfig)) {
    c = loadServerConfigFile(kDefaultConfig);
  }
  if (options.bind_address) c.bind_address = *options.bind_address;
  if (options.port) c.port = *options.port;
  if (options.video_port) c.video.port = *options.video_port;
  if (options.video_dir) c.video.dir = *options.video_dir;
  if (options.no_video) c.video.enabled = false;
  if (options.runs_dir) c.recording.dir = *options.runs_dir;
  if (options.no_record) c.recording.enabled = false;
  if (options.catalog) c.recording.catalog = *options.catalog;
  if (options.shared_runs) c.recording.shared_runs = *options.shared_runs;
  if (options.server_id) c.server_id = *options.server_id;
  if (options.certs_dir) {
    c.tls.ca = *options.certs_dir + "/ca.pem";
    c.tls.cert = *options.certs_dir + "/server.pem";
    c.tls.key = *options.certs_dir + "/server.key";
  }
  c.tls.plaintext = options.plaintext;
  if (options.operator_socket) c.operator_socket = *options.operator_socket;
  if (options.no_foxglove) c.foxglove.enabled = false;
  if (options.foxglove_port) c.foxglove.port = *options.foxglove_port;
  if (options.foxglove_token_file) {
    c.foxglove.token_file = *options.foxglove_token_file;
    c.foxglove.auth = "token";
  }
  if (options.site_map) c.site_map = *options.site_map;
  if (options.sparkplug_broker) {
    const auto colon = options.sparkplug_broker->rfind(':');
    c.sparkplug.enabled = true;
    c.sparkplug.host = options.sparkplug_broker->substr(0, colon);
    c.sparkplug.port = static_cast<uint16_t>(std::stoi(options.sparkplug_broker->substr(colon + 1)));  // checked by parseCli
  }
  c.recording.server_id = catalogServerId(c);
  return c;
}

void writePortFile(const std::string& path, uint16_t port, const std::string& flag) {
  if (const auto why = writeFileAtomically(path, std::to_string(port) + "\n"); !why.empty())
    throw util::StartupError(flag + ": " + why);
}

namespace {

ConsoleMode consoleModeOf(const CliOptions& options) {
  if (options.no_console) return ConsoleMode::kNone;
  if (options.script_path) return ConsoleMode::kScript;
  if (options.interactive || ::isatty(0)) return ConsoleMode::kInteractive;
  return ConsoleMode::kStream;
}

/// The robot's body and sensors for the 3-D scene, from robot.yaml beside the server's config (default: the paper's robot).
scene::Geometry robotGeometry(const std::filesystem::path& robot_yaml) {
  scene::Geometry geometry;
  if (!std::filesystem::exists(robot_yaml)) return geometry;
  try {
    geometry = scene::geometryOf(config::loadRobotConfigFile(robot_yaml.string()));
  } catch (const std::exception& e) {
    log::warn(log::tag::kServer, "the 3-D scene draws the default robot: ", e.what());
  }
  return geometry;
}

/// The recorder, fed by every envelope of the link, with its sources of gains, Hello and scene.
std::unique_ptr<Recorder> startRecorder(const ServerConfig& config, LinkServer& link, RobotRegistry& registry,
                                        scene::SiteMaps& site_maps, const scene::Geometry& geometry) {
  std::unique_ptr<Recorder> recorder;
  try {
    recorder = std::make_unique<Recorder>(config.recording, INSPECT_VERSION);
  } catch (const std::exception& e) {
    throw util::StartupError(std::string("recording: ") + e.what());
  }
  link.addEnvelopeObserver([rec = recorder.get()](const std::string& id, const std::string& address,
                                                  const v1::Envelope& env, bool inbound, uint64_t time_us) {
    rec->onEnvelope(id, address, env, inbound, time_us);
  });
  // The gain set the robot announced (Hello, GAINS_APPLIED events) with its
  // version; else what its latest telemetry shows while tracking (the
  // recorder adds the controller at the run's first tracking telemetry).
  recorder->setGainsSource([&registry](const std::string& robot) {
    const auto snap = registry.snapshot(robot, monoNowNs());
    if (snap && snap->gains_known) return runGainsJson(snap->gains, snap->gains_version);
    return snap && snap->has_telemetry ? gainsJson(snap->telemetry) : std::string("{}");
  });
  recorder->setHelloSource([&registry](const std::string& robot) -> std::optional<v1::Hello> {
    const auto snap = registry.snapshot(robot, monoNowNs());
    if (!snap) return std::nullopt;
    return snap->hello;
  });
  recorder->setScene(&site_maps, geometry);
  const auto& cat = recorder->catalog();
  std::cout << "pc_server: recording runs in " << config.recording.dir << "/ (catalog "
            << (config.recording.catalog.empty() ? "catalog.sqlite" : cat.path())
            << (cat.serverId().empty() ? "" : ", server " + cat.serverId()) << ")";
  if (!recorder->startupReport().empty()) std::cout << "; " << recorder->startupReport();
  std::cout << std::endl;
  return recorder;
}

/// The Sparkplug B edge node (docs/sparkplug.md), started: its spool beside
/// the runs unless sparkplug.spool_file names one, its broker credentials,
/// and with sparkplug.commands an operator service of its own in `ops`.
std::unique_ptr<sparkplug::SparkplugService> startScada(const ServerConfig& config, Recorder* recorder,
                                                        RobotRegistry& registry, LinkServer& link, ControlArbiter& control,
                                                        const Console::Options& copt,
                                                        std::optional<OperatorService>& ops) {
  const auto& sc = config.sparkplug;
  const std::string node = sc.edge_node_id.empty() ? config.server_id : sc.edge_node_id;
  const std::string spool =
      sc.spool_file.empty() ? (recorder ? recorder->config().dir : config.recording.dir) + "/sparkplug-spool.sqlite"
                            : sc.spool_file;
  std::unique_ptr<sparkplug::SparkplugService> scada;
  try {
    if (const auto dir = std::filesystem::path(spool).parent_path(); !dir.empty()) std::filesystem::create_directories(dir);
    scada = std::make_unique<sparkplug::SparkplugService>(
        sc, node, registry,
        [recorder](const std::string& robot) { return recorder ? recorder->activeRun(robot).value_or("") : ""; }, spool);
  } catch (const std::exception& e) {
    throw util::StartupError(std::string("sparkplug.spool_file: ") + e.what());
  }
  if (!sc.credentials_file.empty()) {
    const auto cred = sparkplug::loadCredentials(sc.credentials_file);
    scada->setCredentials(cred.username, cred.password);
  }
  if (sc.commands) {
    ops.emplace(registry, link, &control, OperatorService::Options{copt.ack_timeout_s, copt.max_v_m_s, copt.max_w_rad_s});
    scada->setCommands(&*ops, control.openSession("scada@" + sc.host));
  }
  scada->start();
  std::cout << "pc_server: Sparkplug B edge node " << sc.group_id << "/" << node << " on mqtt" << (sc.ca.empty() ? "" : "s")
            << "://" << sc.host << ":" << sc.port << std::endl;
  return scada;
}

/// The video hub: telemetry from the link (clock offsets), access units to the recorder and the bridge.
std::unique_ptr<VideoHub> startVideo(const ServerConfig& config, const CliOptions& options, LinkServer& link,
                                     Recorder* recorder, std::atomic<foxglove::FoxgloveBridge*>& bridge_ptr) {
  auto video = std::make_unique<VideoHub>(config.video, config.bind_address, link);
  link.addEnvelopeObserver([hub = video.get()](const std::string& id, const std::string& address,
                                               const v1::Envelope& env, bool inbound, uint64_t time_us) {
    if (inbound && env.has_telemetry()) hub->onTelemetry(id, address, env, time_us);
  });
  if (recorder) {
    recorder->setVideoFigures([hub = video.get()](const std::string& robot) -> std::optional<VideoFigures> {
      const auto st = hub->stats(robot);
      if (!st) return std::nullopt;
      return VideoFigures{static_cast<int64_t>(st->frames), static_cast<int64_t>(st->decoded),
                          static_cast<int64_t>(st->lost_packets)};
    });
  }
  // Every intact access unit goes to the run's recording and to the Foxglove clients, as received.
  video->setAccessUnitHook([recorder, &bridge_ptr](const std::string& stream, const video::Frame& f, uint64_t capture_us) {
    const StreamRef s = parseStreamName(stream);
    if (recorder) recorder->onAccessUnit(s.robot, s.head, f, capture_us);
    if (auto* b = bridge_ptr.load()) b->onAccessUnit(s.robot, s.head, f, capture_us);
  });
  video->start();
  std::cout << "pc_server: video on UDP port " << video->port() << ", SDP files in " << config.video.dir << "/"
            << std::endl;
  if (options.video_port_file) writePortFile(*options.video_port_file, video->port(), "--video-port-file");
  return video;
}

/// The Foxglove bridge's options from foxglove: in server.yaml (the token read or made, wss's context).
foxglove::FoxgloveBridge::Options bridgeOptions(const ServerConfig& config, const Console::Options& copt,
                                                VideoHub* video) {
  const auto& fc = config.foxglove;
  foxglove::FoxgloveBridge::Options fo;
  fo.server.bind = fc.bind;
  fo.server.port = fc.port;
  fo.server.name = config.server_id;
  if (fc.auth == "token") fo.server.token = foxglove::loadOrCreateToken(fc.token_file);
  fo.server.allowed_origins = fc.allowed_origins;
  fo.server.max_clients = fc.max_clients;
  if (fc.tls) {
    try {
      fo.server.tls = net::makeTlsContext({"", config.tls.cert, config.tls.key}, net::TlsRole::kWebServer);
    } catch (const net::TlsError& e) {
      throw util::StartupError(std::string("foxglove.tls: ") + e.what());
    }
  }
  fo.scene_hz = fc.scene_hz;
  fo.grid_hz = fc.grid_hz;
  fo.teleop_timeout_s = fc.teleop_timeout_s;
  fo.max_v_m_s = copt.max_v_m_s;
  fo.max_w_rad_s = copt.max_w_rad_s;
  if (video)
    fo.video_stats = [video](const std::string& robot) -> std::optional<v1::VideoReceiveStats> {
      const auto st = video->stats(robot);
      return st ? std::optional(toProto(*st)) : std::nullopt;
    };
  return fo;
}

/// Prints where the bridge listens (and how to get in); writes its port file.
void announceBridge(const ServerConfig& config, const CliOptions& options, uint16_t port) {
  const auto& fc = config.foxglove;
  const std::string url = std::string(fc.tls ? "wss" : "ws") + "://" + (fc.bind == "0.0.0.0" ? "<this-host>" : fc.bind) +
                          ":" + std::to_string(port) + "/";
  std::cout << "pc_server: Foxglove WebSocket on " << url
            << (fc.auth == "token" ? "?token=<the token in " + fc.token_file + ">" : std::string(" (no token: loopback only)"))
            << std::endl;
  if (options.foxglove_port_file) writePortFile(*options.foxglove_port_file, port, "--foxglove-port-file");
}

/// SIGINT and SIGTERM: stop the server; a first SIGINT during a console job (tune) cancels only the job.
void watchSignals(asio::signal_set& signals, StopFlag& stop) {
  signals.async_wait([&signals, &stop](const boost::system::error_code& ec, int sig) {
    if (ec) return;
    if (sig == SIGINT && stop.interrupt()) {
      // A console job (tune) takes Ctrl-C as "cancel, keep the best so far".
      log::info(log::tag::kServer, "SIGINT: cancelling the running console job (Ctrl-C again to shut down)");
      stop.setInterruptTarget(nullptr);
      watchSignals(signals, stop);
      return;
    }
    log::info(log::tag::kServer, "signal ", sig == SIGINT ? "SIGINT" : "SIGTERM", ": shutting down");
    stop.request();
  });
}

/// MCAP chunks of quiet recordings reach the disk within a second.
void tickRecorder(asio::steady_timer& timer, Recorder& recorder) {
  recorder.tick();
  timer.expires_after(std::chrono::milliseconds(200));
  timer.async_wait([&timer, &recorder](const boost::system::error_code& ec) {
    if (!ec) tickRecorder(timer, recorder);
  });
}

/// In a shared catalog: this server's row and its robots' presence every
/// kPresencePeriod (fleet_presence.hpp); `robots --fleet` reads them.
struct PresenceTicker {
  PresenceTicker(asio::io_context& ioc, Recorder& r, RobotRegistry& reg, catalog::ServerInfo i)
      : timer(ioc), recorder(r), registry(reg), info(std::move(i)) {}
  asio::steady_timer timer;
  Recorder& recorder;
  RobotRegistry& registry;
  std::mutex mu;  // the timer's handler and the last write at shutdown may run on two io threads
  catalog::ServerInfo info;

  void write() {
    std::lock_guard lk(mu);
    info.seen = std::chrono::system_clock::now();
    recorder.notePresence(info, presenceOf(registry.snapshots(monoNowNs()), info.id, info.seen));
  }
  void tick() {
    write();
    timer.expires_after(kPresencePeriod);
    timer.async_wait([this](const boost::system::error_code& ec) {
      if (!ec) tick();
    });
  }
};

/// The ticker of a server sharing its catalog (none with a SQLite file). Where an
/// operator attaches: the Foxglove WebSocket, else the robots' link port.
std::unique_ptr<PresenceTicker> startPresence(asio::io_context& ioc, const ServerConfig& config, Recorder* recorder,
                                              RobotRegistry& registry, uint16_t link_port,
                                              std::optional<uint16_t> foxglove_port) {
  if (!recorder || config.recording.server_id.empty()) return nullptr;
  catalog::ServerInfo info;
  info.id = config.recording.server_id;
  const std::string host = hostName().empty() ? "localhost" : hostName();
  info.attach = foxglove_port ? std::string(config.foxglove.tls ? "wss://" : "ws://") + host + ":" +
                                    std::to_string(*foxglove_port)
                              : host + ":" + std::to_string(link_port);
  info.runs_root = recorder->runsRoot();
  info.software_version = INSPECT_VERSION;
  info.started = std::chrono::system_clock::now();
  auto t = std::make_unique<PresenceTicker>(ioc, *recorder, registry, std::move(info));
  t->tick();
  return t;
}

/// The server's own console (by its mode) and the attached ones, until the
/// operator quits or the server is stopped; the exit status (1: the script or stream failed).
int runConsoles(ConsoleMode mode, const std::vector<std::string>& script, const CliOptions& options,
              const ServerConfig& config, RobotRegistry& registry, LinkServer& link, ControlArbiter& control,
              const Console::Options& copt, const std::function<void(Console&)>& configure, StopFlag& stop) {
  int status = 0;
  Console console(registry, link, std::cout, stop, copt);
  configure(console);
  console.setSession(&control, control.openSession(localUserName() + "@console"));
  std::unique_ptr<OperatorSocket> operators;
  if (!config.operator_socket.empty()) {
    operators = std::make_unique<OperatorSocket>(config.operator_socket, registry, link, control, copt, configure);
    operators->start();
    std::cout << "pc_server: operator consoles: pc_server --attach " << config.operator_socket << std::endl;
  }
  console.setAlarmStyle(::isatty(STDOUT_FILENO) == 1);  // red + bell on a terminal, plain text into pipes
  ConsoleRunner runner(console, stop, config.status_refresh_hz);
  switch (mode) {
    case ConsoleMode::kNone:
      stop.wait();
      break;
    case ConsoleMode::kScript:
      status = runner.runScript(script, *options.script_path) ? 0 : 1;
      if (options.interactive && !stop.requested() && !console.quitRequested()) runner.runInteractive();
      break;
    case ConsoleMode::kInteractive:
      runner.runInteractive();
      break;
    case ConsoleMode::kStream:
      status = runner.runStream(0) ? 0 : 1;
      break;
  }
  if (operators) operators->stop();
  return status;
}

}  // namespace

int runServer(const CliOptions& options) {
  const ServerConfig config = resolveConfig(options);
  const ConsoleMode mode = consoleModeOf(options);
  std::vector<std::string> script;
  if (options.script_path) script = readScriptFile(*options.script_path);

  // A console writing to a closed pipe must not kill the server.
  std::signal(SIGPIPE, SIG_IGN);

  // The robot and control configs beside the server's (config/robot.yaml,
  // config/control.yaml): the tuning host reads them, the 3-D scene draws the robot's body and sensors.
  const std::filesystem::path cfg_dir =
      options.config_path ? std::filesystem::path(*options.config_path).parent_path() : std::filesystem::path("config");
  const auto beside = [&](const char* name) { return (cfg_dir.empty() ? std::filesystem::path(".") : cfg_dir) / name; };
  const scene::Geometry geometry = robotGeometry(beside("robot.yaml"));
  scene::SiteMaps site_maps;
  site_maps.setDefault(config.site_map);

  // Declared first, destroyed last: an accept still pending on `ioc` holds a
  // socket of one of the sessions' io_contexts.
  SessionThreads session_threads(kIoThreads);  // started with the io threads, at the end
  asio::io_context ioc;
  RobotRegistry registry;
  LinkServer link(ioc, config, registry, &session_threads);
  link.setLogEvents(mode == ConsoleMode::kNone);
  if (mode != ConsoleMode::kNone) link.setConsoleWatchdog(kConsoleWatchdog);
  // The Foxglove bridge (made once the recorder and the video exist) sees every envelope.
  std::atomic<foxglove::FoxgloveBridge*> bridge_ptr{nullptr};
  link.addEnvelopeObserver([&bridge_ptr](const std::string& id, const std::string&, const v1::Envelope& env,
                                         bool inbound, uint64_t time_us) {
    if (auto* b = bridge_ptr.load()) b->onEnvelope(id, env, inbound, time_us);
  });
  std::atomic<sparkplug::SparkplugService*> scada_ptr{nullptr};
  link.addEnvelopeObserver([&scada_ptr](const std::string& id, const std::string&, const v1::Envelope& env,
                                        bool inbound, uint64_t time_us) {
    if (auto* s = scada_ptr.load()) s->onEnvelope(id, env, inbound, time_us);
  });
  const auto endpoint = link.listen();
  if (config.tls.plaintext) {
    log::warn(log::tag::kServer, net::kPlaintextWarning);
    std::cerr << "pc_server: " << net::kPlaintextWarning << std::endl;
  }
  std::cout << "pc_server: listening on " << endpoint.address().to_string() << ":" << endpoint.port()
            << (config.tls.plaintext ? " (PLAINTEXT)" : " (mutual TLS, server certificate " + link.certificateInfo() + ")")
            << std::endl;
  if (options.port_file) writePortFile(*options.port_file, endpoint.port(), "--port-file");

  std::unique_ptr<Recorder> recorder;
  if (config.recording.enabled) recorder = startRecorder(config, link, registry, site_maps, geometry);
  std::unique_ptr<VideoHub> video;
  if (config.video.enabled) video = startVideo(config, options, link, recorder.get(), bridge_ptr);

  Console::Options copt;
  // Every console (this one, those attached to the operator socket and each
  // Foxglove client) is one session; one session at a time controls a robot (docs/console.md).
  ControlArbiter control;
  const auto configure = [&](Console& c) {
    c.setVideo(video.get());
    c.setRecorder(recorder.get());
    c.setSiteMaps(&site_maps);
    if (auto* b = bridge_ptr.load()) c.setFoxgloveReport([b] { return b->report(); });
    if (auto* sp = scada_ptr.load()) c.setSparkplugReport([sp] { return sp->report(); });
    c.setTuningPaths(beside("robot.yaml").string(), beside("control.yaml").string(),
                     (recorder ? recorder->config().dir : config.recording.dir) + "/tuning");
  };
  std::unique_ptr<foxglove::FoxgloveBridge> bridge;
  std::optional<uint16_t> foxglove_port;
  if (config.foxglove.enabled) {
    auto fo = bridgeOptions(config, copt, video.get());
    fo.recorder = recorder.get();
    bridge = std::make_unique<foxglove::FoxgloveBridge>(ioc, std::move(fo), registry, link, control, site_maps,
                                                        geometry, copt, configure);
    const auto ep = bridge->start();  // a failure here leaves no pointer to a destroyed bridge
    bridge_ptr = bridge.get();
    announceBridge(config, options, ep.port());
    foxglove_port = ep.port();
  }
  auto presence = startPresence(ioc, config, recorder.get(), registry, endpoint.port(), foxglove_port);
  // The plant's SCADA (docs/sparkplug.md): alarm transitions from the link, the rest from the registry.
  std::optional<OperatorService> scada_ops;  // SCADA's operator session: stop and e-stop only (DCMD); outlives scada
  std::unique_ptr<sparkplug::SparkplugService> scada;
  if (config.sparkplug.enabled) {
    scada = startScada(config, recorder.get(), registry, link, control, copt, scada_ops);
    scada_ptr = scada.get();
  }

  StopFlag stop;
  asio::signal_set signals(ioc, SIGINT, SIGTERM);
  watchSignals(signals, stop);
  asio::steady_timer record_timer(ioc);
  if (recorder) tickRecorder(record_timer, *recorder);

  auto work = asio::make_work_guard(ioc);
  IoThreads io{ioc, session_threads, {}};
  session_threads.start();
  for (int i = 0; i < kIoThreads; ++i) io.threads.emplace_back([&ioc] { ioc.run(); });

  const int status = runConsoles(mode, script, options, config, registry, link, control, copt, configure, stop);
  std::cout.flush();
  if (bridge) bridge->stop();
  if (scada) scada->stop();  // the robots' DDEATH and the node's NDEATH while the links still stand

  log::info(log::tag::kServer, "stopping: closing robot sessions");
  link.stop();
  if (!link.waitAllClosed(std::chrono::seconds(1))) log::warn(log::tag::kServer, "some sessions did not close within 1 s");
  asio::post(ioc, [&signals, &record_timer, &presence] {
    boost::system::error_code ignored;
    signals.cancel(ignored);
    record_timer.cancel();
    if (presence) {
      presence->timer.cancel();
      presence->write();  // the robots' links are closed: the fleet sees them offline
    }
  });
  if (video) video->stop();
  work.reset();
  // IoThreads' destructor joins the io threads before the recorder (declared
  // earlier) ends the runs still open.
  return status;  // io stops and joins the threads
}

}  // namespace inspect::server
