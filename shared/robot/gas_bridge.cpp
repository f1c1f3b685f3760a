#include "shared/robot/gas_bridge.hpp"

#include <algorithm>
#include <cstdio>

#include "shared/util/number_text.hpp"

namespace inspect::robot {

const std::string& GasBridge::channelName(int channel) const {
  return monitor_.config().channels[static_cast<std::size_t>(channel)].name;
}

void GasBridge::alarmOf(const gas::AlarmTransition& t, double age_s, double now_s, v1::GasAlarm& a) const {
  const auto& ch = monitor_.config().channels[static_cast<std::size_t>(t.channel)];
  a.set_id(t.id);
  a.set_channel(static_cast<uint32_t>(t.channel));
  a.set_channel_name(ch.name);
  a.set_level(t.level == gas::AlarmLevel::Low    ? v1::GasAlarm::LOW
              : t.level == gas::AlarmLevel::High ? v1::GasAlarm::HIGH
                                                 : v1::GasAlarm::SENSOR_FAULT);
  a.set_active(t.active);
  a.set_value(t.value);
  a.set_threshold(t.threshold);
  a.set_unit(ch.unit);
  // The monitor's times are on the MCU clock; the message's on the robot's.
  a.set_since_us(static_cast<uint64_t>(std::max(0.0, now_s - age_s) * 1e6));
  a.set_fault(t.fault);
  a.set_peak(t.peak);
}

CoreEvent GasBridge::eventOf(const gas::AlarmTransition& t, double now_s, const control::Pose2& pose) const {
  const auto& ch = monitor_.config().channels[static_cast<std::size_t>(t.channel)];
  v1::GasAlarm a;
  alarmOf(t, t.t_s - t.since_s, now_s, a);
  a.mutable_pose()->set_x_m(pose.x_m);
  a.mutable_pose()->set_y_m(pose.y_m);
  a.mutable_pose()->set_theta_rad(pose.theta_rad);
  a.set_robot_time_us(static_cast<uint64_t>(now_s * 1e6));
  char text[200];
  if (t.level == gas::AlarmLevel::SensorFault)
    std::snprintf(text, sizeof text, "gas sensor %s fault %s: %s at (%.2f, %.2f)", ch.name.c_str(),
                  t.active ? "raised" : "cleared", t.fault, pose.x_m, pose.y_m);
  else
    std::snprintf(text, sizeof text, "gas %s %s alarm %s: %.2f %s (threshold %.2f%s) at (%.2f, %.2f)",
                  ch.name.c_str(), gas::levelName(t.level), t.active ? "raised" : "cleared", t.value,
                  ch.unit.c_str(), t.threshold, t.active ? "" : (", peak " + util::fmtFixed(t.peak)).c_str(),
                  pose.x_m, pose.y_m);
  return {t.active ? v1::Event::ALARM_RAISED : v1::Event::ALARM_CLEARED, text, std::move(a), {}, 0};
}

void GasBridge::fillTelemetry(v1::Telemetry& t, double clock_s, double now_s) const {
  t.clear_gas();
  for (int i = 0; i < monitor_.channels(); ++i) t.add_gas(monitor_.value(i));  // NaN = no data
  t.clear_active_alarms();
  active_.clear();
  monitor_.active(active_);
  for (const auto& a : active_) alarmOf(a, clock_s - a.since_s, now_s, *t.add_active_alarms());
}

std::vector<v1::GasChannelInfo> GasBridge::channels() const {
  std::vector<v1::GasChannelInfo> out;
  for (const auto& c : monitor_.config().channels) {
    v1::GasChannelInfo i;
    i.set_name(c.name);
    i.set_gas(c.gas);
    i.set_unit(c.unit);
    i.set_sensor(c.sensor);
    i.set_alarm_low(c.alarm_low);
    i.set_alarm_high(c.alarm_high);
    i.set_falling(c.direction == config::AlarmDirection::Falling);
    i.set_t90_s(c.t90_s);
    i.set_range_min(c.range_min);
    i.set_range_max(c.range_max);
    i.set_background(c.background);
    out.push_back(std::move(i));
  }
  return out;
}

}  // namespace inspect::robot
