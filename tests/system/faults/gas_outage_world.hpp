#pragma once
// What outage_check and soak share: the world whose gas alarms are raised and
// cleared all along, and the readers of the alarm transitions robot_client
// logged and the catalog filed (docs/store-and-forward.md).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace inspect::test {

/// A closed room, the robot at rest; a CH4 leak beside its gas inlet that
/// leaks for 12 s of every 30 s; CO dropping out for 2 s of every 7 s and H2S
/// for 3 s of every 11 s (each a SENSOR_FAULT raised and cleared), up to `duration_s`.
std::string gasOutageWorldYaml(double duration_s);

/// One alarm transition as robot_client logged it ("HH:MM:SS.mmm I [core] ALARM_RAISED: text").
struct LoggedAlarm {
  int64_t ms_of_day;
  std::string kind, text;  // kind: ALARM_RAISED or ALARM_CLEARED
};
/// Every alarm transition in a robot_client log (appended across restarts), in order.
std::vector<LoggedAlarm> robotLoggedAlarms(const std::string& log_path);

/// When a run of the catalog ended (`record stop`), Unix seconds; nullopt while it runs or when not found.
std::optional<double> catalogRunEndUnix(const std::string& db, const std::string& run_id);

/// One row of the catalog's alarms table.
struct CatalogAlarm {
  double time_unix;
  std::string run_id, channel, level, state;
};
/// The catalog's alarms whose `column` ("run_id" or "robot_id") is `value`, by time; empty when unreadable.
std::vector<CatalogAlarm> catalogAlarms(const std::string& db, const std::string& column, const std::string& value);

/// One alarm transition in a run's MCAP (/event).
struct RecordedAlarm {
  uint64_t log_ns;
  std::string kind, text;
  bool late;  // stored by the robot during an outage, sent after it
};
/// The alarm transitions of a run's MCAP, by log time. Throws std::runtime_error (an unreadable file).
std::vector<RecordedAlarm> mcapAlarms(const std::string& path);

/// Local time of day, ms, of a CLOCK_REALTIME instant (what robot_client's log lines carry).
int64_t msOfDayLocal(uint64_t unix_ns);
/// a - b across midnight, ms.
int64_t dayDiffMs(int64_t a, int64_t b);

}  // namespace inspect::test
