#include "pc_server/app/cli_options.hpp"

#include <functional>
#include <map>

#include "pc_server/app/server_config.hpp"
#include "pc_server/console/text_util.hpp"

namespace inspect::server {

namespace {

struct FlagSpec {
  bool takes_value;
  std::function<void(CliOptions&, const std::string&)> apply;
};

const std::map<std::string, FlagSpec>& flags() {
  static const std::map<std::string, FlagSpec> kFlags = {
      {"--config", {true, [](CliOptions& o, const std::string& v) { o.config_path = v; }}},
      {"--bind",
       {true,
        [](CliOptions& o, const std::string& v) {
          if (!validBindAddress(v)) throw UsageError("--bind: '" + v + "' is not a numeric IP address");
          o.bind_address = v;
        }}},
      {"--port",
       {true,
        [](CliOptions& o, const std::string& v) {
          const auto n = parseInteger(v);
          if (!n || *n < 0 || *n > 65535) throw UsageError("--port: '" + v + "' is not a port number (0-65535)");
          o.port = static_cast<uint16_t>(*n);
        }}},
      {"--video-port",
       {true,
        [](CliOptions& o, const std::string& v) {
          const auto n = parseInteger(v);
          if (!n || *n < 0 || *n > 65535) throw UsageError("--video-port: '" + v + "' is not a port number (0-65535)");
          o.video_port = static_cast<uint16_t>(*n);
        }}},
      {"--video-port-file", {true, [](CliOptions& o, const std::string& v) { o.video_port_file = v; }}},
      {"--video-dir", {true, [](CliOptions& o, const std::string& v) { o.video_dir = v; }}},
      {"--no-video", {false, [](CliOptions& o, const std::string&) { o.no_video = true; }}},
      {"--runs-dir", {true, [](CliOptions& o, const std::string& v) { o.runs_dir = v; }}},
      {"--no-record", {false, [](CliOptions& o, const std::string&) { o.no_record = true; }}},
      {"--certs", {true, [](CliOptions& o, const std::string& v) { o.certs_dir = v; }}},
      {"--operator-socket", {true, [](CliOptions& o, const std::string& v) { o.operator_socket = v; }}},
      {"--attach", {true, [](CliOptions& o, const std::string& v) { o.attach = v; }}},
      {"--plaintext", {false, [](CliOptions& o, const std::string&) { o.plaintext = true; }}},
      {"--port-file", {true, [](CliOptions& o, const std::string& v) { o.port_file = v; }}},
      {"--script", {true, [](CliOptions& o, const std::string& v) { o.script_path = v; }}},
      {"--interactive", {false, [](CliOptions& o, const std::string&) { o.interactive = true; }}},
      {"--no-console", {false, [](CliOptions& o, const std::string&) { o.no_console = true; }}},
      {"--help", {false, [](CliOptions& o, const std::string&) { o.help = true; }}},
      {"-h", {false, [](CliOptions& o, const std::string&) { o.help = true; }}},
  };
  return kFlags;
}

}  // namespace

CliOptions parseCli(const std::vector<std::string>& args) {
  CliOptions o;
  for (std::size_t i = 0; i < args.size(); ++i) {
    std::string name = args[i];
    std::optional<std::string> value;
    if (const auto eq = name.find('='); name.rfind("--", 0) == 0 && eq != std::string::npos) {
      value = name.substr(eq + 1);
      name = name.substr(0, eq);
    }
    const auto it = flags().find(name);
    if (it == flags().end()) {
      if (name.empty() || name[0] != '-') throw UsageError("unexpected argument '" + args[i] + "'");
      throw UsageError("unknown flag '" + name + "'");
    }
    if (it->second.takes_value) {
      if (!value) {
        if (i + 1 >= args.size()) throw UsageError(name + ": needs a value");
        value = args[++i];
      }
      if (value->empty()) throw UsageError(name + ": needs a non-empty value");
    } else if (value) {
      throw UsageError(name + ": takes no value");
    }
    it->second.apply(o, value.value_or(""));
  }
  if (o.attach && args.size() != 2)
    throw UsageError("--attach PATH takes no other flags (it only connects to a running server's operator socket)");
  if (o.plaintext && o.certs_dir) throw UsageError("--plaintext cannot be combined with --certs");
  if (o.no_console && (o.script_path || o.interactive))
    throw UsageError("--no-console cannot be combined with --script or --interactive");
  return o;
}

std::string usageText() {
  return "usage: pc_server [options]\n"
         "Operator PC server: accepts robot_client links (TCP, protobuf) and runs the operator console.\n"
         "\n"
         "  --config FILE     server config (default: config/server.yaml if it exists, else built-in defaults)\n"
         "  --bind ADDR       listen address, numeric IPv4/IPv6 (overrides 'bind'; default 0.0.0.0)\n"
         "  --port N          TCP port, 0 = ephemeral (overrides 'port'; default 7600)\n"
         "  --port-file FILE  write the listening port to FILE (atomically) once listening\n"
         "  --video-port N    UDP port of the video receiver, 0 = ephemeral (overrides video.port; default 5600)\n"
         "  --video-port-file FILE  write the video receiver's UDP port to FILE once bound\n"
         "  --video-dir DIR   SDP files and snapshots (overrides video.dir; default video)\n"
         "  --no-video        do not receive video (overrides video.enabled)\n"
         "  --runs-dir DIR    recorded runs and catalog.sqlite (overrides recording.dir; default runs)\n"
         "  --no-record       keep no catalog and record nothing (overrides recording.enabled)\n"
         "  --certs DIR       TLS files DIR/ca.pem, DIR/server.pem, DIR/server.key (overrides tls.*; default certs;\n"
         "                    make them with scripts/make_certs.sh)\n"
         "  --plaintext       no TLS: the robot link is neither encrypted nor authenticated (test benches only;\n"
         "                    warns at start and for every robot; robots must use --plaintext too)\n"
         "  --operator-socket PATH  more operator consoles: `pc_server --attach PATH` connects one (Unix socket,\n"
         "                    mode 0660; overrides operator_socket; each is a session, see 'help control')\n"
         "  --attach PATH     be an operator console of the server listening on PATH, then exit\n"
         "  --script FILE     run the console commands in FILE, then exit (0 = all expects passed, 1 = not)\n"
         "  --interactive     after --script, stay in the interactive console; alone, force the interactive console\n"
         "  --no-console      serve until SIGINT/SIGTERM without reading stdin (service mode)\n"
         "  --help            show this text and exit\n"
         "\n"
         "Without --script the console is interactive when stdin is a terminal; otherwise commands are read\n"
         "from stdin like a script and the server exits at end of input. See docs/console.md.\n"
         "Exit status: 0 ok, 1 script failure, 2 bad command line or config, 3 cannot listen / write port file.\n";
}

}  // namespace inspect::server
