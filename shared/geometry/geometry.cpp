#include <algorithm>
#include <cmath>
#include <cstdio>

#include "shared/geometry/circle.hpp"
#include "shared/geometry/polygon.hpp"
#include "shared/geometry/segment.hpp"
#include "shared/geometry/vec2.hpp"

namespace inspect::geometry {

std::string pointText(Vec2 p) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "(%g, %g)", p.x, p.y);
  return buf;
}

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

Vec2 closestPoint(Vec2 p, const Segment& s) {
  const Vec2 e = s.b - s.a;
  const double len2 = dot(e, e);
  const double u = std::clamp(len2 > 0.0 ? dot(p - s.a, e) / len2 : 0.0, 0.0, 1.0);
  return s.a + u * e;
}

double pointSegmentDistance(Vec2 p, const Segment& s) { return norm(p - closestPoint(p, s)); }

bool segmentsCross(const Segment& s, const Segment& t) {
  const double d1 = cross(s.b - s.a, t.a - s.a), d2 = cross(s.b - s.a, t.b - s.a);
  const double d3 = cross(t.b - t.a, s.a - t.a), d4 = cross(t.b - t.a, s.b - t.a);
  return d1 * d2 < 0 && d3 * d4 < 0;
}

bool segmentsIntersect(const Segment& s, const Segment& t) {
  auto orient = [](Vec2 a, Vec2 b, Vec2 c) {
    const double o = cross(b - a, c - a);
    return (o > 1e-12) - (o < -1e-12);
  };
  auto onSegment = [](Vec2 a, Vec2 b, Vec2 p) {
    return std::min(a.x, b.x) - 1e-12 <= p.x && p.x <= std::max(a.x, b.x) + 1e-12 &&
           std::min(a.y, b.y) - 1e-12 <= p.y && p.y <= std::max(a.y, b.y) + 1e-12;
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

std::optional<double> rayCircle(Vec2 origin, Vec2 dir, const Circle& c) {
  // |origin + t dir - centre|^2 = r^2 with |dir| = 1: t^2 + 2 b t + k = 0.
  const Vec2 oc = origin - c.centre;
  const double k = dot(oc, oc) - c.radius_m * c.radius_m;
  if (k <= 0.0) return 0.0;
  const double b = dot(oc, dir);
  if (b >= 0.0) return std::nullopt;  // outside and heading away
  const double disc = b * b - k;
  if (disc < 0.0) return std::nullopt;
  return -b - std::sqrt(disc);
}

bool pointInPolygon(Vec2 p, const Polygon& poly) {
  bool inside = false;
  const auto& v = poly.vertices;
  for (std::size_t i = 0, j = v.size() - 1; i < v.size(); j = i++) {
    const bool straddles = (v[i].y > p.y) != (v[j].y > p.y);
    if (straddles) {
      const double x_cross = v[j].x + (p.y - v[j].y) * (v[i].x - v[j].x) / (v[i].y - v[j].y);
      if (p.x < x_cross) inside = !inside;
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

}  // namespace inspect::geometry
