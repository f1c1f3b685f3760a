#include "tests/system/faults/gas_outage_world.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <ctime>
#include <fstream>
#include <sstream>

#include "inspect_robot/v1/link.pb.h"
#include "shared/record/mcap_reader.hpp"

namespace inspect::test {

std::string gasOutageWorldYaml(double duration_s) {
  std::ostringstream w;
  w << "name: gas_outages\n"
       "description: outage_check's world (tests/system/faults/gas_outage_world.cpp)\n"
       "start: {x_m: 2.0, y_m: 2.0, theta_rad: 0.0}\n"
       "walls:\n  - points_m: [0.0, 0.0, 6.0, 0.0, 6.0, 4.0, 0.0, 4.0]\n    closed: true\n"
       "gas:\n  diffusivity_m2_s: 0.05\n  ventilation_per_s: 0.2\n  cell_m: 0.1\n  sources:\n";
  for (double t = 2; t < duration_s; t += 30)
    w << "    - {name: pulse" << static_cast<int>(t) << ", gas: CH4, x_m: 2.35, y_m: 2.0, rate: 20.0, start_s: " << t
      << ", end_s: " << t + 12 << "}\n";
  w << "  faults:\n";
  for (double t = 5; t < duration_s; t += 7) w << "    - {channel: CO, kind: dropout, start_s: " << t << ", end_s: " << t + 2 << "}\n";
  for (double t = 8; t < duration_s; t += 11) w << "    - {channel: H2S, kind: dropout, start_s: " << t << ", end_s: " << t + 3 << "}\n";
  return w.str();
}

std::vector<LoggedAlarm> robotLoggedAlarms(const std::string& log_path) {
  std::vector<LoggedAlarm> out;
  std::ifstream in(log_path);
  for (std::string line; std::getline(in, line);) {
    for (const char* kind : {"ALARM_RAISED", "ALARM_CLEARED"}) {
      const std::string tag = std::string("[core] ") + kind + ": ";
      const auto at = line.find(tag);
      if (at == std::string::npos || line.size() < 12) continue;
      try {
        const int64_t ms = ((std::stoll(line.substr(0, 2)) * 60 + std::stoll(line.substr(3, 2))) * 60 +
                            std::stoll(line.substr(6, 2))) * 1000 + std::stoll(line.substr(9, 3));
        out.push_back({ms, kind, line.substr(at + tag.size())});
      } catch (const std::exception&) {
        // Not a log line's time stamp: not a transition.
      }
    }
  }
  return out;
}

std::vector<CatalogAlarm> catalogAlarms(const std::string& db, const std::string& column, const std::string& value) {
  std::vector<CatalogAlarm> out;
  if (column != "run_id" && column != "robot_id") return out;
  sqlite3* h = nullptr;
  if (sqlite3_open_v2(db.c_str(), &h, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    sqlite3_close(h);
    return out;
  }
  const std::string sql = "SELECT time_unix, IFNULL(run_id, ''), channel, level, state FROM alarms WHERE " + column +
                          " = ? ORDER BY time_unix, id";
  sqlite3_stmt* st = nullptr;
  if (sqlite3_prepare_v2(h, sql.c_str(), -1, &st, nullptr) == SQLITE_OK) {
    sqlite3_bind_text(st, 1, value.c_str(), -1, SQLITE_TRANSIENT);
    const auto text = [&](int i) { return std::string(reinterpret_cast<const char*>(sqlite3_column_text(st, i))); };
    while (sqlite3_step(st) == SQLITE_ROW) out.push_back({sqlite3_column_double(st, 0), text(1), text(2), text(3), text(4)});
  }
  sqlite3_finalize(st);
  sqlite3_close(h);
  return out;
}

std::optional<double> catalogRunEndUnix(const std::string& db, const std::string& run_id) {
  sqlite3* h = nullptr;
  std::optional<double> end;
  if (sqlite3_open_v2(db.c_str(), &h, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_stmt* st = nullptr;
    if (sqlite3_prepare_v2(h, "SELECT end_unix FROM runs WHERE run_id = ?", -1, &st, nullptr) == SQLITE_OK) {
      sqlite3_bind_text(st, 1, run_id.c_str(), -1, SQLITE_TRANSIENT);
      if (sqlite3_step(st) == SQLITE_ROW && sqlite3_column_type(st, 0) != SQLITE_NULL) end = sqlite3_column_double(st, 0);
    }
    sqlite3_finalize(st);
  }
  sqlite3_close(h);
  return end;
}

std::vector<RecordedAlarm> mcapAlarms(const std::string& path) {
  std::vector<RecordedAlarm> out;
  auto r = record::McapReader::open(path);
  r.forEach([&](const record::McapMessageView& m) {
    if (!m.topic.ends_with("/events")) return true;  // "/<robot>/events", the robot's own
    v1::Event e;
    if (!e.ParseFromArray(m.data.data(), static_cast<int>(m.data.size()))) return true;
    if (e.kind() == v1::Event::ALARM_RAISED || e.kind() == v1::Event::ALARM_CLEARED)
      out.push_back({m.log_time_ns, v1::Event::Kind_Name(e.kind()), e.text(), e.stored().replayed()});
    return true;
  });
  std::stable_sort(out.begin(), out.end(),
                   [](const RecordedAlarm& a, const RecordedAlarm& b) { return a.log_ns < b.log_ns; });
  return out;
}

int64_t msOfDayLocal(uint64_t unix_ns) {
  const std::time_t s = static_cast<std::time_t>(unix_ns / 1'000'000'000ULL);
  std::tm tm{};
  localtime_r(&s, &tm);
  return ((tm.tm_hour * 60 + tm.tm_min) * 60 + tm.tm_sec) * 1000LL + static_cast<int64_t>(unix_ns / 1'000'000ULL % 1000);
}

int64_t dayDiffMs(int64_t a, int64_t b) {
  int64_t d = a - b;
  if (d > 43'200'000) d -= 86'400'000;
  if (d < -43'200'000) d += 86'400'000;
  return d;
}

}  // namespace inspect::test
