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

GasConfig defaultGasConfig() {
  GasConfig g;
  GasChannel ch4;
  ch4.name = "CH4";
  ch4.gas = "methane";
  ch4.unit = "%LEL";
  ch4.sensor = "catalytic";
  ch4.scale = 0.01;
  ch4.range_max = 100.0;
  ch4.t90_s = 6.0;
  ch4.noise = 0.3;
  ch4.alarm_low = 10.0;
  ch4.alarm_high = 20.0;
  ch4.hysteresis = 2.0;
  ch4.min_duration_s = 1.0;
  g.channels.push_back(ch4);

  GasChannel h2s;
  h2s.name = "H2S";
  h2s.gas = "hydrogen sulfide";
  h2s.unit = "ppm";
  h2s.sensor = "electrochemical";
  h2s.scale = 0.01;
  h2s.range_max = 100.0;
  h2s.t90_s = 8.0;
  h2s.noise = 0.2;
  h2s.alarm_low = 5.0;
  h2s.alarm_high = 10.0;
  h2s.hysteresis = 1.0;
  h2s.min_duration_s = 1.0;
  g.channels.push_back(h2s);

  GasChannel co;
  co.name = "CO";
  co.gas = "carbon monoxide";
  co.unit = "ppm";
  co.sensor = "electrochemical";
  co.scale = 0.1;
  co.range_max = 1000.0;
  co.t90_s = 10.0;
  co.noise = 1.0;
  co.alarm_low = 35.0;
  co.alarm_high = 100.0;
  co.hysteresis = 5.0;
  co.min_duration_s = 1.0;
  co.cross.push_back({"H2S", 0.1});
  g.channels.push_back(co);

  GasChannel o2;
  o2.name = "O2";
  o2.gas = "oxygen";
  o2.unit = "%vol";
  o2.sensor = "electrochemical";
  o2.scale = 0.01;
  o2.range_max = 30.0;
  o2.t90_s = 8.0;
  o2.noise = 0.03;
  o2.background = 20.9;
  o2.direction = AlarmDirection::Falling;
  o2.alarm_low = 19.5;
  o2.alarm_high = 18.0;
  o2.hysteresis = 0.3;
  o2.min_duration_s = 1.0;
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
