#include "pc_server/route_file.hpp"

#include "shared/config/config_node.hpp"

namespace inspect::server {

namespace {

constexpr double kMaxCoordinate_m = 1000.0;

std::string stem(const std::string& file) {
  const auto slash = file.rfind('/');
  std::string s = slash == std::string::npos ? file : file.substr(slash + 1);
  if (s.size() > 5 && s.compare(s.size() - 5, 5, ".yaml") == 0) s.resize(s.size() - 5);
  return s;
}

Route readRoute(const config::ConfigNode& root) {
  Route r;
  r.name = root.string("name", stem(root.file()));
  if (r.name.empty()) root.fail("name", "must not be empty");
  r.speed_m_s = root.number("speed_m_s", r.speed_m_s, 0.0, kMaxRouteSpeed_m_s);
  if (root.has("speed_m_s") && r.speed_m_s <= 0.0) root.fail("speed_m_s", "must be > 0 m/s (leave it out for the robot's default)");
  if (!root.has("waypoints_m")) root.fail("waypoints_m", "required list [x0, y0, x1, y1, ...] is missing");
  r.waypoints_m = root.numbers("waypoints_m");
  const auto n = r.waypoints_m.size();
  if (n == 0) root.fail("waypoints_m", "needs at least one point [x, y]");
  if (n % 2 != 0) root.fail("waypoints_m", std::to_string(n) + " numbers: needs pairs x, y");
  if (n / 2 > kMaxRoutePoints)
    root.fail("waypoints_m", std::to_string(n / 2) + " points: at most " + std::to_string(kMaxRoutePoints));
  for (std::size_t i = 0; i < n; ++i)
    if (r.waypoints_m[i] < -kMaxCoordinate_m || r.waypoints_m[i] > kMaxCoordinate_m)
      root.fail("waypoints_m", "element " + std::to_string(i) + " is outside [-1000, 1000] m");
  root.checkKnown();
  return r;
}

}  // namespace

Route loadRouteFile(const std::string& path) { return readRoute(config::ConfigNode::loadFile(path)); }

Route loadRouteText(const std::string& yaml, const std::string& name) {
  return readRoute(config::ConfigNode::loadString(yaml, name));
}

v1::GoTo goToOf(const Route& r) {
  v1::GoTo g;
  g.set_name(r.name);
  g.set_speed_m_s(r.speed_m_s);
  for (std::size_t i = 0; i + 1 < r.waypoints_m.size(); i += 2) {
    auto* p = g.add_points();
    p->set_x_m(r.waypoints_m[i]);
    p->set_y_m(r.waypoints_m[i + 1]);
  }
  return g;
}

}  // namespace inspect::server
