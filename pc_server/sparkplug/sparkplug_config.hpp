#pragma once
// server.yaml `sparkplug:` (docs/sparkplug.md): pc_server as a Sparkplug B
// edge node on an MQTT broker. Loaded by app/server_config.
#include <cstdint>
#include <string>

namespace inspect::server::sparkplug {

/// A change smaller than these is not published as DDATA.
struct Deadbands {
  double position_m = 0.05;
  double heading_rad = 0.035;   // 2 degrees
  double speed_m_s = 0.02;
  double battery_v = 0.1;
  double person_m = 0.1;
  double gas_fraction = 0.02;   // of the channel's A1 threshold (of its range when A1 is 0)
};

struct SparkplugConfig {
  bool enabled = false;
  std::string host = "127.0.0.1";        // the MQTT broker
  uint16_t port = 1883;                  // 8883 is the usual with TLS
  std::string group_id = "inspection";
  std::string edge_node_id;              // "" = the server's id (server_id)
  std::string primary_host_id;           // "" = none; else births wait for its STATE online (section 7.4)
  std::string credentials_file;          // "username: ..." / "password: ..." (never on the command line); "" = none
  std::string ca;                        // TLS when set: the broker's CA
  std::string cert, key;                 // TLS client certificate (optional)
  int qos = 1;                           // of births, data and deaths: 1 (nothing lost) or 0 (the specification's)
  double keepalive_s = 10;
  double min_period_s = 0.5;             // a robot's DDATA at most this often (alarm events at once)
  bool commands = false;                 // DCMD stop / e-stop from SCADA (never motion)
  std::size_t queue_max = 10000;         // events kept across a broker outage
  std::string spool_file;                // the file they are kept in ("" = <recording.dir>/sparkplug-spool.sqlite)
  Deadbands deadbands;
};

}  // namespace inspect::server::sparkplug
