#include "shared/world/gas_spec.hpp"

#include <cmath>
#include <cstdio>

#include "shared/world/world.hpp"

namespace inspect::world {
namespace {

using config::ConfigNode;

constexpr double kMaxTime_s = 1e9;

bool validName(const std::string& s, std::size_t max_len, bool allow_dot) {
  if (s.empty() || s.size() > max_len) return false;
  for (char c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
                    c == '-' || (allow_dot && c == '.');
    if (!ok) return false;
  }
  return true;
}

// end_s: absent = never ends.
double readEnd(const ConfigNode& n, double start_s) {
  const double end_s = n.number("end_s", std::numeric_limits<double>::infinity(), -kMaxTime_s, kMaxTime_s);
  if (end_s <= start_s) n.fail("end_s", "must be later than start_s");
  return end_s;
}

GasSource readSource(const ConfigNode& n, std::size_t index, const World& world, double ventilation_per_s) {
  GasSource s;
  s.name = n.string("name", "leak" + std::to_string(index));
  if (!validName(s.name, 64, true)) n.fail("name", "'" + s.name + "' must be 1 to 64 letters, digits, '_', '-' or '.'");
  s.gas = n.requireString("gas");
  if (!validName(s.gas, 16, false)) n.fail("gas", "'" + s.gas + "' is not a gas channel name ([A-Za-z0-9_-]{1,16})");
  s.position.x = n.requireNumber("x_m", -kMaxCoord_m, kMaxCoord_m);
  s.position.y = n.requireNumber("y_m", -kMaxCoord_m, kMaxCoord_m);
  s.rate = n.requireNumber("rate", 0.0, 1e6);
  if (s.rate <= 0.0) n.fail("rate", "must be positive");
  s.start_s = n.number("start_s", 0.0, -kMaxTime_s, kMaxTime_s);
  if (ventilation_per_s == 0.0 && s.start_s < -kGasMaxPreRunNoVentilation_s)
    n.fail("start_s",
           "with gas.ventilation_per_s 0 the field never settles; a leak may start at most 600 s before t = 0");
  s.end_s = readEnd(n, s.start_s);

  const auto box = solidBounds(world);
  if (!box) n.fail("x_m", "a world with leaks needs walls or obstacles (the gas grid covers their bounding box)");
  const Vec2 p = s.position;
  if (p.x <= box->lo.x || p.x >= box->hi.x || p.y <= box->lo.y || p.y >= box->hi.y)
    n.fail("x_m", "leak at " + pointText(p) + " lies outside the walls' bounding box " + pointText(box->lo) + " .. " +
                      pointText(box->hi));
  for (const auto& o : world.obstacles)
    if (geometry::pointInPolygon(p, o.polygon))
      n.fail("x_m", "leak at " + pointText(p) + " lies inside obstacle '" + o.name + "'");
  if (clearance(world, p) < 1e-6) n.fail("x_m", "leak at " + pointText(p) + " lies on a wall or obstacle edge");
  return s;
}

GasFault readFault(const ConfigNode& n) {
  GasFault f;
  f.channel = n.requireString("channel");
  if (!validName(f.channel, 16, false))
    n.fail("channel", "'" + f.channel + "' is not a gas channel name ([A-Za-z0-9_-]{1,16})");
  if (!n.has("kind")) n.fail("kind", "required: stuck or dropout");
  f.kind = n.oneOf("kind", "stuck", {"stuck", "dropout"}) == "stuck" ? GasFaultKind::Stuck : GasFaultKind::Dropout;
  f.start_s = n.number("start_s", 0.0, 0.0, kMaxTime_s);
  f.end_s = readEnd(n, f.start_s);
  return f;
}

}  // namespace

GasSpec readGasSpec(const ConfigNode& root, const World& world) {
  GasSpec g;
  const auto n = root.optChild("gas");
  g.diffusivity_m2_s = n.number("diffusivity_m2_s", g.diffusivity_m2_s, 0.0, 10.0);
  if (g.diffusivity_m2_s <= 0.0) n.fail("diffusivity_m2_s", "must be positive");
  g.ventilation_per_s = n.number("ventilation_per_s", g.ventilation_per_s, 0.0, 10.0);
  if (n.has("airflow_m_s")) {
    const auto u = n.numbers("airflow_m_s", 2);
    for (double v : u)
      if (v < -5.0 || v > 5.0) n.fail("airflow_m_s", "each component must lie in [-5, 5] m/s");
    g.airflow_m_s = {u[0], u[1]};
  }
  g.cell_m = n.number("cell_m", g.cell_m, 0.02, 1.0);

  const auto sources = n.children("sources");
  for (std::size_t i = 0; i < sources.size(); ++i) {
    GasSource s = readSource(sources[i], i, world, g.ventilation_per_s);
    for (std::size_t j = 0; j < g.sources.size(); ++j)
      if (g.sources[j].name == s.name)
        sources[i].fail("name", "'" + s.name + "' is already used by gas.sources[" + std::to_string(j) + "]");
    g.sources.push_back(std::move(s));
  }
  for (const auto& f : n.children("faults")) g.faults.push_back(readFault(f));
  return g;
}

}  // namespace inspect::world
