#include "shared/world/world.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>

namespace inspect::world {
namespace {

using config::ConfigNode;

constexpr double kMaxAngle_rad = 6.2832;

template <class F>
void forEachSolidEdge(const World& w, F&& f) {
  for (const auto& s : w.walls) f(s);
  for (const auto& o : w.obstacles) {
    const auto& v = o.polygon.vertices;
    for (std::size_t i = 0; i < v.size(); ++i) f(Segment{v[i], v[(i + 1) % v.size()]});
  }
}

Vec2 readPoint(const ConfigNode& n, const std::string& key) {
  const auto xy = n.numbers(key, 2);
  for (double v : xy)
    if (std::abs(v) > kMaxCoord_m) n.fail(key, "coordinates must lie in [-1000, 1000] m");
  return {xy[0], xy[1]};
}

// A flat list x0, y0, x1, y1, ... of at least min_points points.
std::vector<Vec2> readPoints(const ConfigNode& n, const std::string& key, std::size_t min_points) {
  if (!n.has(key)) n.fail(key, "required list of coordinates is missing");
  const auto xy = n.numbers(key);
  if (xy.size() % 2 != 0) n.fail(key, "must list x, y pairs (an even count of numbers), has " + std::to_string(xy.size()));
  if (xy.size() / 2 < min_points)
    n.fail(key, "needs at least " + std::to_string(min_points) + " points, has " + std::to_string(xy.size() / 2));
  std::vector<Vec2> pts;
  for (std::size_t i = 0; i < xy.size(); i += 2) {
    if (std::abs(xy[i]) > kMaxCoord_m || std::abs(xy[i + 1]) > kMaxCoord_m)
      n.fail(key, "coordinates must lie in [-1000, 1000] m");
    pts.push_back({xy[i], xy[i + 1]});
  }
  return pts;
}

// Either {from_m, to_m} (one segment) or {points_m, closed} (a polyline).
std::vector<Segment> readSegments(const ConfigNode& n) {
  const bool single = n.has("from_m") || n.has("to_m");
  const bool poly = n.has("points_m");
  if (single && poly) n.fail("points_m", "give either from_m/to_m or points_m, not both");
  if (!single && !poly) n.fail("from_m", "required: from_m and to_m, or points_m");
  std::vector<Segment> out;
  if (single) {
    const Segment s{readPoint(n, "from_m"), readPoint(n, "to_m")};
    if (std::hypot(s.b.x - s.a.x, s.b.y - s.a.y) < 1e-6) n.fail("to_m", "segment has zero length");
    out.push_back(s);
    return out;
  }
  const auto pts = readPoints(n, "points_m", 2);
  const bool closed = n.boolean("closed", false);
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) out.push_back({pts[i], pts[i + 1]});
  if (closed) {
    if (pts.size() < 3) n.fail("closed", "a closed polyline needs at least 3 points");
    out.push_back({pts.back(), pts.front()});
  }
  for (std::size_t i = 0; i < out.size(); ++i)
    if (std::hypot(out[i].b.x - out[i].a.x, out[i].b.y - out[i].a.y) < 1e-6)
      n.fail("points_m", "segment " + std::to_string(i) + " has zero length (repeated point)");
  return out;
}

Polygon readPolygon(const ConfigNode& n) {
  Polygon p{readPoints(n, "vertices_m", 3)};
  if (std::abs(geometry::signedArea(p)) < 1e-6) n.fail("vertices_m", "polygon has no area (degenerate)");
  const auto edges = geometry::edgesOf(p);
  const std::size_t m = edges.size();
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = i + 1; j < m; ++j) {
      const bool adjacent = j == i + 1 || (i == 0 && j == m - 1);
      if (adjacent) continue;
      if (geometry::segmentsIntersect(edges[i], edges[j]))
        n.fail("vertices_m", "edges " + std::to_string(i) + " and " + std::to_string(j) +
                                 " cross or touch; an obstacle must be a simple polygon");
    }
  }
  return p;
}

}  // namespace

double clearance(const World& w, Vec2 p) {
  for (const auto& o : w.obstacles)
    if (geometry::pointInPolygon(p, o.polygon)) return 0.0;
  double best = std::numeric_limits<double>::infinity();
  forEachSolidEdge(w, [&](const Segment& s) { best = std::min(best, geometry::pointSegmentDistance(p, s)); });
  return best;
}

std::optional<double> castRay(const World& w, Vec2 origin, double yaw_rad, double max_range_m) {
  const Vec2 dir{std::cos(yaw_rad), std::sin(yaw_rad)};
  std::optional<double> best;
  forEachSolidEdge(w, [&](const Segment& s) {
    const auto t = geometry::raySegment(origin, dir, s);
    if (t && *t <= max_range_m && (!best || *t < *best)) best = t;
  });
  return best;
}

std::vector<behavior::WallSegment> solidEdges(const World& w) {
  std::vector<behavior::WallSegment> out;
  forEachSolidEdge(w, [&](const Segment& s) { out.push_back({s}); });
  // Corners of polylines and polygons (or separate walls meeting end to end).
  const auto same = [](Vec2 p, Vec2 q) { return norm(p - q) < 1e-9; };
  for (std::size_t i = 0; i < out.size(); ++i) {
    for (std::size_t j = 0; j < out.size(); ++j) {
      if (i == j) continue;
      const Segment &p = out[i].edge, &q = out[j].edge;
      out[i].a_joined = out[i].a_joined || same(p.a, q.a) || same(p.a, q.b);
      out[i].b_joined = out[i].b_joined || same(p.b, q.a) || same(p.b, q.b);
    }
  }
  return out;
}

std::optional<Bounds> solidBounds(const World& w) {
  std::optional<Bounds> b;
  forEachSolidEdge(w, [&](const Segment& s) {
    for (const Vec2 p : {s.a, s.b}) {
      if (!b) b = Bounds{p, p};
      b->lo = {std::min(b->lo.x, p.x), std::min(b->lo.y, p.y)};
      b->hi = {std::max(b->hi.x, p.x), std::max(b->hi.y, p.y)};
    }
  });
  return b;
}

bool onFloorLine(const World& w, Vec2 p) {
  for (const auto& l : w.floor_lines)
    if (geometry::pointSegmentDistance(p, l.centre) <= l.width_m / 2.0) return true;
  return false;
}

World loadWorld(const ConfigNode& root) {
  World w;
  w.source_file = root.file();
  w.name = root.string("name", std::filesystem::path(root.file()).stem().string());
  if (w.name.empty()) root.fail("name", "must not be empty");
  w.description = root.string("description", "");

  const auto s = root.optChild("start");
  w.start.x_m = s.number("x_m", 0.0, -kMaxCoord_m, kMaxCoord_m);
  w.start.y_m = s.number("y_m", 0.0, -kMaxCoord_m, kMaxCoord_m);
  w.start.theta_rad = control::wrapAngle(s.number("theta_rad", 0.0, -kMaxAngle_rad, kMaxAngle_rad));

  for (const auto& n : root.children("walls")) {
    for (const auto& seg : readSegments(n)) w.walls.push_back(seg);
  }
  for (const auto& n : root.children("obstacles")) {
    Obstacle o;
    o.name = n.string("name", "obstacle" + std::to_string(w.obstacles.size()));
    o.polygon = readPolygon(n);
    w.obstacles.push_back(std::move(o));
  }
  for (const auto& n : root.children("floor_lines")) {
    const double width_m = n.number("width_m", 0.025, 0.001, 1.0);
    for (const auto& seg : readSegments(n)) w.floor_lines.push_back({seg, width_m});
  }
  // After walls and obstacles: routes are checked against them.
  w.pedestrians = readPedestrianScripts(root, w);
  w.social_force = behavior::readSocialForceParams(root.optChild("social_force"));
  w.gas = readGasSpec(root, w);
  if (root.has("plant")) {
    // The robot's true hub motors; each wheel's keys default to the nominal
    // motor (gain 1, no dead time); saturation 0 = the robot's wheel limit.
    const auto p = root.child("plant");
    control::PlantModel pm;
    const double tau = p.number("time_constant_s", 0.20, 0.001, 5.0);
    const double dead = p.number("dead_time_s", 0.0, 0.0, 1.0);
    auto wheel = [&](const char* key, control::WheelMotorModel& m) {
      const auto n = p.optChild(key);
      m.gain = n.number("gain", 1.0, 0.2, 5.0);
      m.time_constant_s = n.number("time_constant_s", tau, 0.001, 5.0);
      m.dead_time_s = n.number("dead_time_s", dead, 0.0, 1.0);
      m.saturation_rad_s = n.number("saturation_rad_s", 0.0, 0.0, 100.0);
    };
    wheel("left", pm.left);
    wheel("right", pm.right);
    w.plant = pm;
  }
  return w;
}

namespace {
World loadChecked(const ConfigNode& root) {
  World w = loadWorld(root);
  root.checkKnown();
  return w;
}
}  // namespace

World loadWorldFile(const std::string& path) { return loadChecked(ConfigNode::loadFile(path)); }

World loadWorldText(const std::string& yaml, const std::string& name) {
  return loadChecked(ConfigNode::loadString(yaml, name));
}

void checkStartPose(const World& world, double body_radius_m) {
  const double c = clearance(world, {world.start.x_m, world.start.y_m});
  if (c < body_radius_m) {
    std::ostringstream os;
    os << world.source_file << ": start: the robot (body radius " << body_radius_m << " m) at (" << world.start.x_m
       << ", " << world.start.y_m << ") overlaps a wall or obstacle (clearance " << c << " m)";
    throw config::ConfigError(os.str());
  }
}

}  // namespace inspect::world
