#include "pc_server/operator/route_file.hpp"

#include <cmath>
#include <sys/stat.h>

#include "shared/config/config_node.hpp"
#include "shared/util/number_text.hpp"

namespace inspect::server {

namespace {

constexpr double kMaxCoordinate_m = 1000.0;

std::string stem(const std::string& file) {
  const auto slash = file.rfind('/');
  std::string s = slash == std::string::npos ? file : file.substr(slash + 1);
  if (s.size() > 5 && s.compare(s.size() - 5, 5, ".yaml") == 0) s.resize(s.size() - 5);
  return s;
}

bool exists(const std::string& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0;
}

// A relative map path is tried as given (working directory), then beside the
// route file's directory's parent (config/routes/x.yaml -> config/worlds/...).
std::string resolveMap(const config::ConfigNode& root, const std::string& map) {
  if (map.empty() || map.front() == '/' || exists(map)) {
    if (!map.empty() && !exists(map)) root.fail("map", "'" + map + "' does not exist");
    return map;
  }
  const std::string& file = root.file();
  const auto slash = file.rfind('/');
  const std::string dir = slash == std::string::npos ? "." : file.substr(0, slash);
  for (const std::string& cand : {dir + "/../../" + map, dir + "/../" + map, dir + "/" + map})
    if (exists(cand)) return cand;
  root.fail("map", "'" + map + "' does not exist (tried the working directory and beside the route file)");
}

// `wheel_test: {standard: <amplitude_rad_s>}` or `wheel_test: {segments: [{kind, duration_s, left_rad_s,
// right_rad_s, f0_hz, f1_hz}, ...]}`; the profile is checked against a 30 rad/s ceiling here (the robot
// checks its own wheel limit).
void readWheelTest(const config::ConfigNode& root, Route& r) {
  using K = control::WheelProfileSegment::Kind;
  constexpr double kCeiling_rad_s = 30.0;
  const auto w = root.child("wheel_test");
  if (w.has("standard") == w.has("segments")) root.fail("wheel_test", "give either `standard: <amplitude_rad_s>` or `segments`");
  if (w.has("standard")) {
    const double a = w.number("standard", 2.0, 0.1, kCeiling_rad_s);
    const double max = w.number("max_wheel_rad_s", 5.0, 0.1, kCeiling_rad_s);
    if (a > max) w.fail("standard", "amplitude above max_wheel_rad_s");
    r.wheel_test = control::WheelProfile::standardIdentification(a, max).segments();
  } else {
    for (const auto& n : w.children("segments")) {
      control::WheelProfileSegment g;
      const std::string kind = n.oneOf("kind", "step", {"hold", "step", "chirp"});
      g.kind = kind == "hold" ? K::kHold : kind == "chirp" ? K::kChirp : K::kStep;
      g.duration_s = n.requireNumber("duration_s", 0.001, 600.0);
      g.left_rad_s = n.number("left_rad_s", 0.0, -kCeiling_rad_s, kCeiling_rad_s);
      g.right_rad_s = n.number("right_rad_s", 0.0, -kCeiling_rad_s, kCeiling_rad_s);
      if (g.kind == K::kChirp) {
        g.f0_hz = n.requireNumber("f0_hz", 0.001, 20.0);
        g.f1_hz = n.requireNumber("f1_hz", 0.001, 20.0);
      }
      r.wheel_test.push_back(g);
    }
    if (r.wheel_test.empty()) w.fail("segments", "needs at least one segment");
    try {
      control::WheelProfile check(r.wheel_test, kCeiling_rad_s);
    } catch (const std::invalid_argument& e) {
      w.fail("segments", e.what());
    }
  }
}

Route readRoute(const config::ConfigNode& root) {
  Route r;
  r.file = root.file();
  r.name = root.string("name", stem(root.file()));
  if (r.name.empty()) root.fail("name", "must not be empty");
  r.speed_m_s = root.number("speed_m_s", r.speed_m_s, 0.0, kMaxCommandSpeed_m_s);
  if (root.has("speed_m_s") && r.speed_m_s <= 0.0) root.fail("speed_m_s", "must be > 0 m/s (leave it out for the robot's default)");
  const std::string map = root.string("map", "");
  if (root.has("wheel_test")) {
    if (root.has("waypoints_m") || root.has("points")) root.fail("wheel_test", "a wheel test has no points");
    readWheelTest(root, r);
    r.map = resolveMap(root, map);
    root.checkKnown();
    return r;
  }
  const bool flat = root.has("waypoints_m"), listed = root.has("points");
  if (!flat && !listed)
    root.fail("waypoints_m", "required list [x0, y0, x1, y1, ...] is missing (or give `points`)");
  if (flat && listed) root.fail("points", "give either waypoints_m or points, not both");
  if (flat) {
    const auto w = root.numbers("waypoints_m");
    const auto n = w.size();
    if (n == 0) root.fail("waypoints_m", "needs at least one point [x, y]");
    if (n % 2 != 0) root.fail("waypoints_m", std::to_string(n) + " numbers: needs pairs x, y");
    if (n / 2 > kMaxRoutePoints)
      root.fail("waypoints_m", std::to_string(n / 2) + " points: at most " + std::to_string(kMaxRoutePoints));
    for (std::size_t i = 0; i < n; ++i)
      if (w[i] < -kMaxCoordinate_m || w[i] > kMaxCoordinate_m)
        root.fail("waypoints_m", "element " + std::to_string(i) + " is outside [-1000, 1000] m");
    for (std::size_t i = 0; i + 1 < n; i += 2) r.points.push_back({w[i], w[i + 1], 0.0, std::nullopt, ""});
  } else {
    const auto pts = root.children("points");
    if (pts.empty()) root.fail("points", "needs at least one point {at: [x, y]}");
    if (pts.size() > static_cast<std::size_t>(kMaxRoutePoints))
      root.fail("points", std::to_string(pts.size()) + " points: at most " + std::to_string(kMaxRoutePoints));
    for (const auto& p : pts) {
      RoutePoint rp;
      const auto at = p.numbers("at", 2);
      for (int k = 0; k < 2; ++k)
        if (!(std::abs(at[static_cast<std::size_t>(k)]) <= kMaxCoordinate_m))
          p.fail("at", "coordinates must be within [-1000, 1000] m");
      rp.x_m = at[0];
      rp.y_m = at[1];
      rp.dwell_s = p.number("dwell_s", 0.0, 0.0, kMaxDwell_s);
      rp.label = p.string("label", "");
      if (p.has("ptz")) {
        const auto z = p.child("ptz");
        v1::Ptz ptz;
        if (z.boolean("home", false)) {
          ptz.set_home(true);
        } else {
          ptz.set_pan_rad(z.number("pan_deg", 0.0, -180.0, 180.0) * M_PI / 180.0);
          ptz.set_tilt_rad(z.number("tilt_deg", 0.0, -90.0, 90.0) * M_PI / 180.0);
        }
        rp.ptz = ptz;
      }
      r.points.push_back(rp);
    }
  }
  r.map = resolveMap(root, map);
  root.checkKnown();
  return r;
}

}  // namespace

std::vector<double> Route::waypointsM() const {
  std::vector<double> w;
  for (const auto& p : points) {
    w.push_back(p.x_m);
    w.push_back(p.y_m);
  }
  return w;
}

int Route::inspectionPoints() const {
  int n = 0;
  for (const auto& p : points) n += p.dwell_s > 0.0;
  return n;
}

Route loadRouteFile(const std::string& path) { return readRoute(config::ConfigNode::loadFile(path)); }

Route loadRouteText(const std::string& yaml, const std::string& name) {
  return readRoute(config::ConfigNode::loadString(yaml, name));
}

std::string resolveRoute(const std::string& name_or_path) {
  if (exists(name_or_path)) return name_or_path;
  if (name_or_path.find('/') == std::string::npos) {
    const std::string p = "config/routes/" + name_or_path + (name_or_path.ends_with(".yaml") ? "" : ".yaml");
    if (exists(p)) return p;
  }
  throw config::ConfigError("no route '" + name_or_path + "': neither a file nor config/routes/" + name_or_path +
                            ".yaml");
}

Route openRoute(const std::string& name_or_path) {
  const bool path = name_or_path.find('/') != std::string::npos || name_or_path.ends_with(".yaml");
  return loadRouteFile(path ? name_or_path : resolveRoute(name_or_path));
}

std::string routeSummary(const Route& r, bool inspection) {
  const std::string speed = r.speed_m_s > 0 ? " at " + util::fmtShort(r.speed_m_s) + " m/s" : std::string();
  if (r.isWheelTest()) {
    double total = 0.0;
    for (const auto& g : r.wheel_test) total += g.duration_s;
    return "wheel test '" + r.name + "': " + std::to_string(r.wheel_test.size()) + " segments, " +
           util::fmtShort(total, 1) + " s of open-loop steps and chirps (identify <run> fits the plant afterwards)";
  }
  if (!inspection) return "route '" + r.name + "': " + std::to_string(r.points.size()) + " points" + speed;
  return "inspection '" + r.name + "': " + std::to_string(r.points.size()) + " points, " +
         std::to_string(r.inspectionPoints()) + " inspection points" + speed + (r.map.empty() ? "" : ", map " + r.map);
}

v1::WheelTest wheelTestOf(const Route& r) {
  v1::WheelTest w;
  w.set_name(r.name);
  for (const auto& g : r.wheel_test) {
    auto* s = w.add_segments();
    s->set_kind(control::toString(g.kind));
    s->set_duration_s(g.duration_s);
    s->set_left_rad_s(g.left_rad_s);
    s->set_right_rad_s(g.right_rad_s);
    s->set_f0_hz(g.f0_hz);
    s->set_f1_hz(g.f1_hz);
  }
  return w;
}

v1::GoTo goToOf(const Route& r, bool inspection) {
  v1::GoTo g;
  g.set_name(r.name);
  g.set_speed_m_s(r.speed_m_s);
  g.set_inspection(inspection);
  for (const auto& rp : r.points) {
    auto* p = g.add_points();
    p->set_x_m(rp.x_m);
    p->set_y_m(rp.y_m);
    if (rp.dwell_s > 0.0) p->set_dwell_s(rp.dwell_s);
    if (rp.ptz) *p->mutable_ptz() = *rp.ptz;
    if (!rp.label.empty()) p->set_label(rp.label);
  }
  return g;
}

}  // namespace inspect::server
