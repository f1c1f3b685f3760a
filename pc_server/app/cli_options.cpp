#include "pc_server/app/cli_options.hpp"

#include "pc_server/app/server_config.hpp"
#include "shared/catalog/sql_backend.hpp"

namespace inspect::server {

CliOptions parseCli(const std::vector<std::string>& args) {
  CliOptions o;
  cli::ArgReader a(args);
  int flags = 0;
  while (a.next()) {
    ++flags;
    if (a.isHelp()) o.help = true;
    else if (a.is("--config")) o.config_path = a.path();
    else if (a.is("--bind")) {
      o.bind_address = a.path();
      if (!validBindAddress(*o.bind_address)) a.fail("'" + *o.bind_address + "' is not a numeric IP address");
    } else if (a.is("--port")) o.port = a.port();
    else if (a.is("--video-port")) o.video_port = a.port();
    else if (a.is("--video-port-file")) o.video_port_file = a.path();
    else if (a.is("--video-dir")) o.video_dir = a.path();
    else if (a.is("--no-video")) o.no_video = true;
    else if (a.is("--runs-dir")) o.runs_dir = a.path();
    else if (a.is("--no-record")) o.no_record = true;
    else if (a.is("--catalog")) {
      o.catalog = a.path();
      // The command line is in `ps` for every user of the machine.
      if (catalog::redactUrl(*o.catalog) != *o.catalog)
        a.fail("the URL carries a password, which ps shows to every user; put it in ~/.pgpass, PGPASSFILE or "
               "PGPASSWORD, or in recording.catalog of the config file");
    } else if (a.is("--shared-runs")) {
      o.shared_runs = a.path();
    } else if (a.is("--server-id")) {
      o.server_id = a.path();
      if (o.server_id->size() > 64) a.fail("must be 1 to 64 characters (as server_id)");
    }
    else if (a.is("--certs")) o.certs_dir = a.path();
    else if (a.is("--no-foxglove")) o.no_foxglove = true;
    else if (a.is("--foxglove-port")) o.foxglove_port = a.port();
    else if (a.is("--foxglove-port-file")) o.foxglove_port_file = a.path();
    else if (a.is("--foxglove-token-file")) o.foxglove_token_file = a.path();
    else if (a.is("--site-map")) o.site_map = a.path();
    else if (a.is("--sparkplug-broker")) {
      o.sparkplug_broker = a.path();
      const auto colon = o.sparkplug_broker->rfind(':');
      if (colon == std::string::npos || colon == 0 || colon + 1 == o.sparkplug_broker->size() ||
          o.sparkplug_broker->find_first_not_of("0123456789", colon + 1) != std::string::npos ||
          o.sparkplug_broker->size() - colon - 1 > 5 || std::stoi(o.sparkplug_broker->substr(colon + 1)) < 1 ||
          std::stoi(o.sparkplug_broker->substr(colon + 1)) > 65535)
        a.fail("'" + *o.sparkplug_broker + "' is not HOST:PORT (e.g. 127.0.0.1:1883)");
    }
    else if (a.is("--operator-socket")) o.operator_socket = a.path();
    else if (a.is("--attach")) o.attach = a.path();
    else if (a.is("--plaintext")) o.plaintext = true;
    else if (a.is("--port-file")) o.port_file = a.path();
    else if (a.is("--script")) o.script_path = a.path();
    else if (a.is("--interactive")) o.interactive = true;
    else if (a.is("--no-console")) o.no_console = true;
    else a.unknown();
  }
  if (o.attach && flags != 1)
    throw cli::UsageError("--attach PATH takes no other flags (it only connects to a running server's operator socket)");
  if (o.plaintext && o.certs_dir) throw cli::UsageError("--plaintext cannot be combined with --certs");
  if (o.no_console && (o.script_path || o.interactive))
    throw cli::UsageError("--no-console cannot be combined with --script or --interactive");
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
         "  --catalog URL|FILE  the run catalog: a SQLite file or a postgresql:// URL that several servers share\n"
         "                    (overrides recording.catalog; default DIR/catalog.sqlite); no password in the URL:\n"
         "                    libpq reads it from ~/.pgpass, PGPASSFILE or PGPASSWORD\n"
         "  --shared-runs DIR  a runs root the fleet's servers share: ended runs are copied to DIR/<server>/<run-id>/\n"
         "                    for other servers' report, export and replay (overrides recording.shared_runs)\n"
         "  --server-id ID    this server's name (overrides server_id): in HelloReply, and its id in a shared\n"
         "                    catalog (where the default pc_server stands for the host name)\n"
         "  --certs DIR       TLS files DIR/ca.pem, DIR/server.pem, DIR/server.key (overrides tls.*; default certs;\n"
         "                    make them with scripts/make_certs.sh)\n"
         "  --plaintext       no TLS: the robot link is neither encrypted nor authenticated (test benches only;\n"
         "                    warns at start and for every robot; robots must use --plaintext too)\n"
         "  --no-foxglove     no Foxglove WebSocket bridge (overrides foxglove.enabled; docs/foxglove.md)\n"
         "  --foxglove-port N the bridge's TCP port, 0 = ephemeral (overrides foxglove.port; default 8765)\n"
         "  --foxglove-port-file FILE  write the bridge's port to FILE once listening\n"
         "  --foxglove-token-file FILE  the bridge's token (read, or created with a new random token; mode 0600)\n"
         "  --site-map FILE   world file drawn in every robot's 3-D scene (overrides site_map; a route's map wins)\n"
         "  --sparkplug-broker HOST:PORT  publish to SCADA as a Sparkplug B edge node on this MQTT broker\n"
         "                    (turns sparkplug.enabled on; credentials only from sparkplug.credentials_file;\n"
         "                    docs/sparkplug.md)\n"
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
         "Exit status: 0 ok, 1 script failure, 2 bad command line or config, 3 cannot start (listen, write the\n"
         "port file, open the catalog).\n";
}

}  // namespace inspect::server
