#include "pc_server/sparkplug/transition_spool.hpp"

#include <array>
#include <string_view>

#include "shared/catalog/sql_backend.hpp"

namespace inspect::server::sparkplug {

namespace {
constexpr std::array<std::string_view, 1> kMigrations = {
    "CREATE TABLE sparkplug_transitions (seq INTEGER PRIMARY KEY AUTOINCREMENT, device TEXT NOT NULL, "
    "alarm_id INTEGER NOT NULL, channel INTEGER NOT NULL, channel_name TEXT NOT NULL, level INTEGER NOT NULL, "
    "active INTEGER NOT NULL, value REAL, robot_time_us INTEGER NOT NULL, time_ms INTEGER NOT NULL, "
    "late INTEGER NOT NULL)"};

int64_t asInt(const catalog::SqlValue& v) { return std::holds_alternative<int64_t>(v) ? std::get<int64_t>(v) : 0; }
}  // namespace

TransitionSpool::TransitionSpool(const std::string& path) : path_(path), db_(catalog::openSqlite(path, kMigrations)) {}

TransitionSpool::~TransitionSpool() = default;

int64_t TransitionSpool::append(const std::string& device, const v1::GasAlarm& a, uint64_t time_ms, bool late) {
  const auto r = db_->run(
      "INSERT INTO sparkplug_transitions (device, alarm_id, channel, channel_name, level, active, value, robot_time_us, "
      "time_ms, late) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?) RETURNING seq",
      {device, static_cast<int64_t>(a.id()), static_cast<int64_t>(a.channel()), a.channel_name(),
       static_cast<int64_t>(a.level()), int64_t{a.active() ? 1 : 0}, a.value(),
       static_cast<int64_t>(a.robot_time_us()), static_cast<int64_t>(time_ms), int64_t{late ? 1 : 0}});
  return r.rows.empty() ? 0 : asInt(r.rows[0][0]);
}

void TransitionSpool::remove(int64_t seq) { db_->run("DELETE FROM sparkplug_transitions WHERE seq = ?", {seq}); }

std::vector<SpooledTransition> TransitionSpool::all() {
  const auto r = db_->run(
      "SELECT seq, device, alarm_id, channel, channel_name, level, active, value, robot_time_us, time_ms, late "
      "FROM sparkplug_transitions ORDER BY seq",
      {});
  std::vector<SpooledTransition> out;
  for (const auto& row : r.rows) {
    SpooledTransition t;
    t.seq = asInt(row[0]);
    t.device = std::get<std::string>(row[1]);
    t.alarm.set_id(static_cast<uint64_t>(asInt(row[2])));
    t.alarm.set_channel(static_cast<uint32_t>(asInt(row[3])));
    t.alarm.set_channel_name(std::get<std::string>(row[4]));
    t.alarm.set_level(static_cast<v1::GasAlarm::Level>(asInt(row[5])));
    t.alarm.set_active(asInt(row[6]) != 0);
    t.alarm.set_value(std::holds_alternative<double>(row[7]) ? std::get<double>(row[7]) : NAN);
    t.alarm.set_robot_time_us(static_cast<uint64_t>(asInt(row[8])));
    t.time_ms = static_cast<uint64_t>(asInt(row[9]));
    t.late = asInt(row[10]) != 0;
    out.push_back(std::move(t));
  }
  return out;
}

}  // namespace inspect::server::sparkplug
