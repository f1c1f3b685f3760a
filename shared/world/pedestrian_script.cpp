#include "shared/world/pedestrian_script.hpp"

#include <cmath>
#include <cstdio>

#include "shared/world/world.hpp"

namespace inspect::world {
namespace {


bool validId(const std::string& id) {
  if (id.empty() || id.size() > 64) return false;
  for (char c : id) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
                    c == '-' || c == '.';
    if (!ok) return false;
  }
  return true;
}

PedestrianScript readOne(const config::ConfigNode& n, std::size_t index, const World& world) {
  PedestrianScript s;
  s.id = n.string("id", "person" + std::to_string(index));
  if (!validId(s.id)) n.fail("id", "'" + s.id + "' must be 1 to 64 letters, digits, '_', '-' or '.'");
  s.radius_m = n.number("radius_m", s.radius_m, 0.05, 1.0);
  s.speed_m_s = n.number("speed_m_s", s.speed_m_s, 0.05, 3.0);
  s.start_s = n.number("start_s", s.start_s, 0.0, 1e6);
  s.arrive_m = n.number("arrive_m", s.arrive_m, 0.01, 5.0);
  s.loop = n.boolean("loop", false);
  s.notices_robot = n.boolean("notices_robot", true);

  if (!n.has("route_m")) n.fail("route_m", "required list of waypoints [x0, y0, x1, y1, ...] is missing");
  const auto xy = n.numbers("route_m");
  if (xy.size() % 2 != 0)
    n.fail("route_m", "must list x, y pairs (an even count of numbers), has " + std::to_string(xy.size()));
  if (xy.empty()) n.fail("route_m", "needs at least 1 point (the start position)");
  for (std::size_t i = 0; i < xy.size(); i += 2) {
    if (std::abs(xy[i]) > kMaxCoord_m || std::abs(xy[i + 1]) > kMaxCoord_m)
      n.fail("route_m", "coordinates must lie in [-1000, 1000] m");
    s.route.push_back({xy[i], xy[i + 1]});
  }
  for (std::size_t i = 0; i + 1 < s.route.size(); ++i) {
    const Vec2 d = s.route[i + 1] - s.route[i];
    if (std::hypot(d.x, d.y) < 1e-6)
      n.fail("route_m", "points " + std::to_string(i) + " and " + std::to_string(i + 1) + " are the same");
  }
  for (std::size_t i = 0; i < s.route.size(); ++i) {
    const double c = clearance(world, s.route[i]);
    if (c < s.radius_m)
      n.fail("route_m", "point " + std::to_string(i) + " " + pointText(s.route[i]) + " is closer than radius_m (" +
                            std::to_string(s.radius_m) + " m) to a wall or inside an obstacle");
  }
  if (s.loop && s.route.size() < 2) n.fail("loop", "a looping route needs at least 2 points");

  const auto pauses = n.children("pauses");
  for (std::size_t k = 0; k < pauses.size(); ++k) {
    const auto& pn = pauses[k];
    PedestrianPause p;
    if (!pn.has("at")) pn.fail("at", "required waypoint index is missing");
    p.at = static_cast<std::size_t>(pn.integer("at", 0, 0, static_cast<long>(s.route.size()) - 1));
    p.duration_s = pn.requireNumber("s", 0.001, 1e6);
    for (const auto& q : s.pauses)
      if (q.at == p.at) pn.fail("at", "waypoint " + std::to_string(p.at) + " already has a pause");
    s.pauses.push_back(p);
  }
  return s;
}

}  // namespace

std::vector<PedestrianScript> readPedestrianScripts(const config::ConfigNode& root, const World& world) {
  std::vector<PedestrianScript> out;
  const auto list = root.children("pedestrians");
  for (std::size_t i = 0; i < list.size(); ++i) {
    PedestrianScript s = readOne(list[i], i, world);
    for (std::size_t j = 0; j < out.size(); ++j)
      if (out[j].id == s.id) list[i].fail("id", "'" + s.id + "' is already used by pedestrians[" + std::to_string(j) + "]");
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace inspect::world
