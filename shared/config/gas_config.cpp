#include "shared/config/gas_config.hpp"

#include <cctype>
#include <cmath>

namespace inspect::config {

double GasChannel::tau_s() const { return t90_s / std::log(10.0); }

int GasConfig::find(const std::string& name) const {
  for (std::size_t i = 0; i < channels.size(); ++i)
    if (channels[i].name == name) return static_cast<int>(i);
  return -1;
}

namespace {

// One row of the default table: what differs between the four sensors.
GasChannel channel(const char* name, const char* gas, const char* unit, const char* sensor, double scale,
                   double range_max, double t90_s, double noise, double alarm_low, double alarm_high,
                   double hysteresis) {
  GasChannel c;
  c.name = name;
  c.gas = gas;
  c.unit = unit;
  c.sensor = sensor;
  c.scale = scale;
  c.range_max = range_max;
  c.t90_s = t90_s;
  c.noise = noise;
  c.alarm_low = alarm_low;
  c.alarm_high = alarm_high;
  c.hysteresis = hysteresis;
  c.min_duration_s = 1.0;
  return c;
}

}  // namespace

GasConfig defaultGasConfig() {
  GasConfig g;
  // name, gas, unit, sensor, scale (unit per count), range max, T90 (s), noise, A1, A2, hysteresis
  g.channels.push_back(channel("CH4", "methane", "%LEL", "catalytic", 0.01, 100.0, 6.0, 0.3, 10.0, 20.0, 2.0));
  g.channels.push_back(channel("H2S", "hydrogen sulfide", "ppm", "electrochemical", 0.01, 100.0, 8.0, 0.2, 5.0, 10.0, 1.0));
  GasChannel co = channel("CO", "carbon monoxide", "ppm", "electrochemical", 0.1, 1000.0, 10.0, 1.0, 35.0, 100.0, 5.0);
  co.cross.push_back({"H2S", 0.1});
  g.channels.push_back(co);
  GasChannel o2 = channel("O2", "oxygen", "%vol", "electrochemical", 0.01, 30.0, 8.0, 0.03, 19.5, 18.0, 0.3);
  o2.background = 20.9;
  o2.direction = AlarmDirection::Falling;
  o2.cross.push_back({"CH4", -0.0105});  // 1 %LEL CH4 = 0.05 %vol displaces 0.0105 %vol O2
  g.channels.push_back(o2);
  return g;
}

GasConfig loadGasConfig(const ConfigNode& section, bool present) {
  GasConfig g;
  if (!present) return g;
  g.inlet_x_m = section.number("inlet_x_m", g.inlet_x_m, -5.0, 5.0);
  g.inlet_y_m = section.number("inlet_y_m", g.inlet_y_m, -5.0, 5.0);
  const auto list = section.children("channels");
  if (list.size() > 4) section.fail("channels", "at most 4 gas channels (the sensor frame has 4 slots)");
  for (const auto& n : list) {
    GasChannel c;
    c.name = n.requireString("name");
    if (c.name.empty() || c.name.size() > 16) n.fail("name", "must be 1 to 16 characters");
    for (char ch : c.name)
      if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-'))
        n.fail("name", "'" + c.name + "': use letters, digits, '_' or '-'");
    if (g.find(c.name) >= 0) n.fail("name", "'" + c.name + "' is listed twice");
    c.gas = n.string("gas", c.name);
    c.unit = n.requireString("unit");
    c.sensor = n.oneOf("sensor", c.sensor, {"catalytic", "electrochemical", "ndir", "pid", "paramagnetic"});
    c.scale = n.number("scale", c.scale, 1e-6, 1e3);
    c.range_min = n.number("range_min", c.range_min, -1e6, 1e6);
    c.range_max = n.requireNumber("range_max", -1e6, 1e6);
    if (c.range_max <= c.range_min) n.fail("range_max", "must exceed range_min");
    if (c.range_max > c.scale * kGasRawMax)
      n.fail("range_max", "exceeds what the raw counts can carry (scale x 65534)");
    c.t90_s = n.number("t90_s", c.t90_s, 0.01, 600.0);
    c.noise = n.number("noise", c.noise, 0.0, 1e6);
    c.background = n.number("background", c.background, c.range_min, c.range_max);
    c.direction = n.oneOf("direction", "rising", {"rising", "falling"}) == "rising" ? AlarmDirection::Rising
                                                                                   : AlarmDirection::Falling;
    c.alarm_low = n.requireNumber("alarm_low", c.range_min, c.range_max);
    c.alarm_high = n.requireNumber("alarm_high", c.range_min, c.range_max);
    if (c.direction == AlarmDirection::Rising && c.alarm_high <= c.alarm_low)
      n.fail("alarm_high", "must exceed alarm_low for a rising alarm");
    if (c.direction == AlarmDirection::Falling && c.alarm_high >= c.alarm_low)
      n.fail("alarm_high", "must be below alarm_low for a falling (low-side) alarm");
    if (c.beyond(c.background, c.alarm_low)) n.fail("alarm_low", "the background value would already be in alarm");
    c.hysteresis = n.number("hysteresis", c.hysteresis, 0.0, c.range_max - c.range_min);
    c.min_duration_s = n.number("min_duration_s", c.min_duration_s, 0.0, 60.0);
    c.stuck_s = n.number("stuck_s", c.stuck_s, 0.5, 3600.0);
    for (const auto& x : n.children("cross_sensitivity")) {
      CrossSensitivity cs;
      cs.gas = x.requireString("gas");
      cs.factor = x.requireNumber("factor", -100.0, 100.0);
      c.cross.push_back(cs);
    }
    g.channels.push_back(c);
  }
  for (std::size_t i = 0; i < list.size(); ++i)
    for (const auto& cs : g.channels[i].cross)
      if (g.find(cs.gas) < 0 || cs.gas == g.channels[i].name)
        list[i].fail("cross_sensitivity", "'" + cs.gas + "' is not another configured channel");
  return g;
}

}  // namespace inspect::config
