#include "shared/world/geometry.hpp"

#include <cstdio>

#include <algorithm>
#include <cmath>

namespace inspect::world {

std::string pointText(Vec2 p) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "(%g, %g)", p.x_m, p.y_m);
  return buf;
}

}  // namespace inspect::world

namespace inspect::world::geom {

std::optional<double> raySegment(Vec2 origin, Vec2 dir, const Segment& s) {
  const Vec2 e = s.b - s.a;
  const double denom = cross(dir, e);
  if (std::abs(denom) < 1e-12) return std::nullopt;
  const Vec2 ao = s.a - origin;
  const double t = cross(ao, e) / denom;
  const double u = cross(ao, dir) / denom;
  if (t < 0.0 || u < 0.0 || u > 1.0) return std::nullopt;
  return t;
}

double pointSegmentDistance(Vec2 p, const Segment& s) {
  const Vec2 e = s.b - s.a;
  const double len2 = dot(e, e);
  double u = len2 > 0.0 ? dot(p - s.a, e) / len2 : 0.0;
  u = std::clamp(u, 0.0, 1.0);
  const Vec2 d = p - (s.a + u * e);
  return std::hypot(d.x_m, d.y_m);
}

bool pointInPolygon(Vec2 p, const Polygon& poly) {
  bool inside = false;
  const auto& v = poly.vertices;
  for (std::size_t i = 0, j = v.size() - 1; i < v.size(); j = i++) {
    const bool straddles = (v[i].y_m > p.y_m) != (v[j].y_m > p.y_m);
    if (straddles) {
      const double x_cross = v[j].x_m + (p.y_m - v[j].y_m) * (v[i].x_m - v[j].x_m) / (v[i].y_m - v[j].y_m);
      if (p.x_m < x_cross) inside = !inside;
    }
  }
  return inside;
}

std::vector<Segment> edgesOf(const Polygon& poly) {
  std::vector<Segment> out;
  const auto& v = poly.vertices;
  for (std::size_t i = 0; i < v.size(); ++i) out.push_back({v[i], v[(i + 1) % v.size()]});
  return out;
}

double signedArea(const Polygon& poly) {
  double a = 0.0;
  const auto& v = poly.vertices;
  for (std::size_t i = 0; i < v.size(); ++i) a += cross(v[i], v[(i + 1) % v.size()]);
  return a / 2.0;
}

bool segmentsIntersect(const Segment& s, const Segment& t) {
  auto orient = [](Vec2 a, Vec2 b, Vec2 c) {
    const double o = cross(b - a, c - a);
    return (o > 1e-12) - (o < -1e-12);
  };
  auto onSegment = [](Vec2 a, Vec2 b, Vec2 p) {
    return std::min(a.x_m, b.x_m) - 1e-12 <= p.x_m && p.x_m <= std::max(a.x_m, b.x_m) + 1e-12 &&
           std::min(a.y_m, b.y_m) - 1e-12 <= p.y_m && p.y_m <= std::max(a.y_m, b.y_m) + 1e-12;
  };
  const int o1 = orient(s.a, s.b, t.a);
  const int o2 = orient(s.a, s.b, t.b);
  const int o3 = orient(t.a, t.b, s.a);
  const int o4 = orient(t.a, t.b, s.b);
  if (o1 != o2 && o3 != o4) return true;
  if (o1 == 0 && onSegment(s.a, s.b, t.a)) return true;
  if (o2 == 0 && onSegment(s.a, s.b, t.b)) return true;
  if (o3 == 0 && onSegment(t.a, t.b, s.a)) return true;
  if (o4 == 0 && onSegment(t.a, t.b, s.b)) return true;
  return false;
}

}  // namespace inspect::world::geom
