#include "pc_server/sparkplug/device_metrics.hpp"

#include <cmath>

namespace inspect::server::sparkplug {

std::string alarmMetricName(const std::string& channel, v1::GasAlarm::Level level) {
  const char* suffix = level == v1::GasAlarm::LOW ? "A1" : level == v1::GasAlarm::HIGH ? "A2" : "Sensor Fault";
  return "Gas/" + channel + "/" + suffix;
}

std::vector<Metric> deviceMetrics(const v1::Hello& hello, const v1::Telemetry& t, const std::string& run,
                                  const Deadbands& db) {
  std::vector<Metric> m;
  m.reserve(16 + 6 * static_cast<std::size_t>(hello.gas_channels_size()));
  m.push_back(Metric::ofString("Mode", v1::Mode_IsValid(t.mode()) ? v1::Mode_Name(t.mode()) : "UNKNOWN"));
  m.push_back(Metric::ofUInt32("Faults", t.faults()));
  m.push_back(Metric::ofDouble("Pose/x_m", t.pose().x_m(), db.position_m));
  m.push_back(Metric::ofDouble("Pose/y_m", t.pose().y_m(), db.position_m));
  m.push_back(Metric::ofDouble("Pose/theta_rad", t.pose().theta_rad(), db.heading_rad));
  m.push_back(Metric::ofDouble("Speed/v_m_s", t.has_v_m_s() ? t.v_m_s() : NAN, db.speed_m_s));
  m.push_back(Metric::ofDouble("Battery/V", t.has_battery_v() ? t.battery_v() : NAN, db.battery_v));
  m.push_back(Metric::ofUInt32("People/Tracked", t.people_tracked()));
  const double nearest = t.has_nearest_person_m() && t.nearest_person_m() >= 0 ? t.nearest_person_m() : NAN;
  m.push_back(Metric::ofDouble("People/Nearest_m", nearest, db.person_m));
  m.push_back(Metric::ofString("Run/Recording", run));
  // DCMD's writable metrics (Boolean true = do it) and the last command's answer, set by events only.
  for (Metric c : {Metric::ofBool(kCommandStop, false), Metric::ofBool(kCommandEStop, false),
                   Metric::ofString(kCommandResult, "")}) {
    c.event_driven = true;
    m.push_back(std::move(c));
  }
  for (int i = 0; i < hello.gas_channels_size(); ++i) {
    const auto& c = hello.gas_channels(i);
    const double scale = c.alarm_low() != 0 ? std::abs(c.alarm_low()) : std::abs(c.range_max() - c.range_min());
    m.push_back(Metric::ofDouble("Gas/" + c.name() + "/Value", i < t.gas_size() ? t.gas(i) : NAN, db.gas_fraction * scale));
    m.push_back(Metric::ofString("Gas/" + c.name() + "/Unit", c.unit()));
    for (const auto level : {v1::GasAlarm::LOW, v1::GasAlarm::HIGH, v1::GasAlarm::SENSOR_FAULT}) {
      bool active = false;
      for (const auto& a : t.active_alarms())
        active = active || (a.channel() == static_cast<uint32_t>(i) && a.level() == level);
      // The level, and the id and reading of its latest transition (events() sets them).
      const std::string name = alarmMetricName(c.name(), level);
      for (Metric a : {Metric::ofBool(name, active), Metric::ofUInt64(name + "/Alarm Id", 0),
                       Metric::ofDouble(name + "/Reading", NAN)}) {
        a.event_driven = true;
        m.push_back(std::move(a));
      }
    }
  }
  return m;
}

std::vector<Metric> alarmOnlyMetrics(const v1::GasAlarm& a) {
  const std::string name = alarmMetricName(a.channel_name(), a.level());
  return {Metric::ofBool(name, false), Metric::ofUInt64(name + "/Alarm Id", 0), Metric::ofDouble(name + "/Reading", NAN)};
}

std::vector<Metric> alarmEventMetrics(const v1::GasAlarm& a, uint64_t time_ms, bool historical) {
  const std::string name = alarmMetricName(a.channel_name(), a.level());
  std::vector<Metric> m{Metric::ofBool(name, a.active()), Metric::ofUInt64(name + "/Alarm Id", a.id()),
                        Metric::ofDouble(name + "/Reading", a.value())};
  for (auto& x : m) {
    x.timestamp_ms = time_ms;
    x.historical = historical;
  }
  return m;
}

}  // namespace inspect::server::sparkplug
