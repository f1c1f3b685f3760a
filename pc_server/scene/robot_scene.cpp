#include "pc_server/scene/robot_scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

#include "pc_server/scene/foxglove_fields.hpp"
#include "shared/world/world.hpp"

namespace inspect::server::scene {

namespace {

constexpr double kGasSamplePeriodS = 0.1;  // the live map takes a reading this often
constexpr double kLagWindowS = 1.0;        // as the report's lag compensation (LagCompensationOptions)
constexpr double kWallHeightM = 1.2;
constexpr double kObstacleHeightM = 0.9;
// Hall's proxemic zones (PAPER_DIGEST.md): intimate, personal, social.
constexpr std::array<double, 3> kProxemicM{0.45, 1.20, 3.60};

struct Quat {
  double w = 1, x = 0, y = 0, z = 0;
};
Quat operator*(const Quat& a, const Quat& b) {
  return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
          a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}
Quat yawQ(double yaw) { return {std::cos(yaw / 2), 0, 0, std::sin(yaw / 2)}; }
Quat pitchQ(double pitch) { return {std::cos(pitch / 2), 0, std::sin(pitch / 2), 0}; }

void setQ(::foxglove::Quaternion* q, const Quat& v) {
  q->set_w(v.w);
  q->set_x(v.x);
  q->set_y(v.y);
  q->set_z(v.z);
}
void setPose(::foxglove::Pose* p, double x, double y, double z, const Quat& q = {}) {
  p->mutable_position()->set_x(x);
  p->mutable_position()->set_y(y);
  p->mutable_position()->set_z(z);
  setQ(p->mutable_orientation(), q);
}
void setVec(::foxglove::Vector3* v, double x, double y, double z) {
  v->set_x(x);
  v->set_y(y);
  v->set_z(z);
}
void addPoint(::foxglove::LinePrimitive* l, double x, double y, double z) {
  auto* p = l->add_points();
  p->set_x(x);
  p->set_y(y);
  p->set_z(z);
}
void addPoint(::foxglove::TriangleListPrimitive* t, double x, double y, double z) {
  auto* p = t->add_points();
  p->set_x(x);
  p->set_y(y);
  p->set_z(z);
}
::foxglove::SceneEntity* entity(::foxglove::SceneUpdate& u, const std::string& id, const std::string& frame, uint64_t ns,
                              bool frame_locked = false) {
  auto* e = u.add_entities();
  e->set_id(id);
  e->set_frame_id(frame);
  setTime(e->mutable_timestamp(), ns);
  e->set_frame_locked(frame_locked);
  return e;
}
void addText(::foxglove::SceneEntity* e, const std::string& text, double x, double y, double z, double size = 0.18) {
  auto* t = e->add_texts();
  setPose(t->mutable_pose(), x, y, z);
  t->set_billboard(true);
  t->set_font_size(size);
  t->set_scale_invariant(false);
  setColor(t->mutable_color(), 1, 1, 1, 1);
  t->set_text(text);
}
void addWall(::foxglove::SceneEntity* e, const geometry::Segment& s, double height, double thickness,
             const std::array<double, 4>& rgba) {
  const double dx = s.b.x - s.a.x, dy = s.b.y - s.a.y;
  const double len = std::hypot(dx, dy);
  if (len < 1e-6) return;
  auto* c = e->add_cubes();
  setPose(c->mutable_pose(), (s.a.x + s.b.x) / 2, (s.a.y + s.b.y) / 2, height / 2, yawQ(std::atan2(dy, dx)));
  setVec(c->mutable_size(), len + thickness, thickness, height);
  setColor(c->mutable_color(), rgba[0], rgba[1], rgba[2], rgba[3]);
}

std::array<double, 3> patternColor(v1::HumanPattern p) {
  switch (p) {
    case v1::CROSSING: return {1.0, 0.55, 0.0};
    case v1::ENCOUNTERING: return {1.0, 0.85, 0.1};
    case v1::LEADING: return {0.2, 0.8, 0.3};
    case v1::CONFRONTING: return {0.95, 0.15, 0.15};
    default: return {0.55, 0.65, 0.9};
  }
}
std::string patternName(v1::HumanPattern p) {
  switch (p) {
    case v1::CROSSING: return "crossing";
    case v1::ENCOUNTERING: return "encountering";
    case v1::LEADING: return "leading";
    case v1::CONFRONTING: return "confronting";
    default: return "";
  }
}
std::string fmt(double v, int digits = 2) {
  char b[32];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}

/// A colour scale from clean air (blue) through the low alarm (yellow) to the high one (red).
std::array<uint8_t, 3> gasColor(double v, const v1::GasChannelInfo& ch) {
  // Clean air at 0, the HIGH threshold at 1, for rising and falling (O2) channels alike.
  const double lo = ch.background();
  const double hi = ch.alarm_high() != lo ? ch.alarm_high() : (ch.range_max() > lo ? ch.range_max() : lo + 1);
  double u = (v - lo) / (hi - lo);
  if (!std::isfinite(u)) u = 0;
  u = std::clamp(u, 0.0, 1.0);
  const auto lerp = [](double a, double b, double t) { return static_cast<uint8_t>(std::lround(a + (b - a) * t)); };
  if (u < 0.5) {
    const double t = u / 0.5;
    return {lerp(40, 250, t), lerp(90, 220, t), lerp(220, 40, t)};
  }
  const double t = (u - 0.5) / 0.5;
  return {lerp(250, 220, t), lerp(220, 20, t), lerp(40, 20, t)};
}

}  // namespace

Geometry geometryOf(const config::RobotConfig& c) {
  Geometry g;
  g.body_radius_m = c.geometry.body_radius_m;
  g.sonars = c.ultrasonic.mounts;
  g.sonar_beam_rad = c.ultrasonic.beam_width_rad;
  g.sonar_max_m = c.ultrasonic.max_range_m;
  g.camera_x_m = c.camera.x_m;
  g.camera_y_m = c.camera.y_m;
  g.camera_z_m = c.camera.z_m;
  if (c.wide_camera) {
    g.wide_camera = true;
    g.wide_camera_x_m = c.wide_camera->x_m;
    g.wide_camera_y_m = c.wide_camera->y_m;
    g.wide_camera_z_m = c.wide_camera->z_m;
    g.wide_camera_tilt_deg = c.wide_camera->tilt_deg;
  }
  return g;
}

SiteMap siteMapOf(const world::World& w) {
  SiteMap m;
  m.name = w.name;
  m.walls = w.walls;
  for (const auto& o : w.obstacles) {
    const auto& v = o.polygon.vertices;
    for (std::size_t i = 0; i < v.size(); ++i) m.obstacles.push_back({v[i], v[(i + 1) % v.size()]});
  }
  for (const auto& l : w.floor_lines) m.floor_lines.push_back(l.centre);
  m.start_x_m = w.start.x_m;
  m.start_y_m = w.start.y_m;
  m.start_theta_rad = w.start.theta_rad;
  return m;
}

RobotScene::RobotScene(std::string robot_id, Geometry geometry) : robot_(std::move(robot_id)), g_(geometry) {}

void RobotScene::setMap(std::optional<SiteMap> map) { map_ = std::move(map); }

void RobotScene::onHello(const v1::Hello& hello) {
  hello_ = hello;
  // A new Hello with the same channels keeps the maps (a reconnect mid-run).
  bool same = static_cast<int>(channels_.size()) == hello.gas_channels_size();
  for (int i = 0; same && i < hello.gas_channels_size(); ++i) same = channels_[i].info.name() == hello.gas_channels(i).name();
  if (same) return;
  channels_.clear();
  gas::MapOptions o;
  o.cell_m = 0.2;  // the report's kernel; a coarser grid for the live view (a 20 m x 10 m site: 5000 cells)
  o.max_cells = 250'000;
  for (const auto& ch : hello.gas_channels()) channels_.push_back({ch, gas::LiveConcentrationMap(o), {}, -1});
}

void RobotScene::onTelemetry(const v1::Telemetry& t) {
  last_ = t;
  have_telemetry_ = true;
  addGas(t, static_cast<double>(t.robot_time_us()) * 1e-6);
}

void RobotScene::addGas(const v1::Telemetry& t, double t_s) {
  const double c = std::cos(t.pose().theta_rad()), s = std::sin(t.pose().theta_rad());
  const double ix = hello_.gas_inlet_x_m(), iy = hello_.gas_inlet_y_m();
  const double x = t.pose().x_m() + c * ix - s * iy, y = t.pose().y_m() + s * ix + c * iy;
  for (std::size_t i = 0; i < channels_.size() && static_cast<int>(i) < t.gas_size(); ++i) {
    Channel& ch = channels_[i];
    if (!ch.window.empty() && t_s < ch.window.back().t_s) {
      // The robot's clock started again (robot_client restarted): a new series, the map kept.
      ch.window.clear();
      ch.last_sample_s = -1;
    }
    if (ch.last_sample_s >= 0 && t_s - ch.last_sample_s < kGasSamplePeriodS && t_s >= ch.last_sample_s) continue;
    ch.last_sample_s = t_s;
    ch.window.push_back({t_s, x, y, t.gas(static_cast<int>(i))});
    while (ch.window.size() > 1 && ch.window.back().t_s - ch.window.front().t_s > kLagWindowS) ch.window.pop_front();
    // The sample in the middle of the last second, with the sensor's lag undone
    // as the report does (compensateLag): the live map trails by half a second.
    const std::vector<gas::GasSample> win(ch.window.begin(), ch.window.end());
    const double tau = ch.info.t90_s() > 0 ? ch.info.t90_s() / std::numbers::ln10 : 0.0;
    const auto comp = gas::compensateLag(win, tau);
    ch.map.add(comp[comp.size() / 2]);
  }
}

void RobotScene::onCommand(const v1::Command& c) {
  if (c.has_go_to()) {
    route_.assign(c.go_to().points().begin(), c.go_to().points().end());
    route_name_ = c.go_to().name();
  }
}

void RobotScene::onEvent(const v1::Event& e) {
  if (!e.has_gas_alarm()) return;
  if (e.kind() != v1::Event::ALARM_RAISED && e.kind() != v1::Event::ALARM_CLEARED) return;
  auto& a = alarms_[e.gas_alarm().id()];
  if (e.kind() == v1::Event::ALARM_RAISED) a.alarm = e.gas_alarm();  // the marker stays where it was raised
  else if (!a.alarm.has_pose()) a.alarm = e.gas_alarm();
  a.active = e.kind() == v1::Event::ALARM_RAISED;
  while (alarms_.size() > kMaxAlarms) alarms_.erase(alarms_.begin());
}

::foxglove::FrameTransforms RobotScene::transforms(uint64_t ns) const {
  ::foxglove::FrameTransforms out;
  const auto add = [&](const std::string& parent, const std::string& child, double x, double y, double z,
                       const Quat& q) {
    auto* t = out.add_transforms();
    setTime(t->mutable_timestamp(), ns);
    t->set_parent_frame_id(parent);
    t->set_child_frame_id(child);
    setVec(t->mutable_translation(), x, y, z);
    setQ(t->mutable_rotation(), q);
  };
  if (map_) add("map", frame("odom"), map_->start_x_m, map_->start_y_m, 0, yawQ(map_->start_theta_rad));
  else add("map", frame("odom"), 0, 0, 0, {});
  const auto& p = last_.pose();
  add(frame("odom"), frame("base_link"), p.x_m(), p.y_m(), 0, yawQ(p.theta_rad()));
  for (std::size_t i = 0; i < kSonarNames.size(); ++i)
    add(frame("base_link"), frame(kSonarNames[i]), g_.sonars[i].x_m, g_.sonars[i].y_m, g_.sonar_z_m,
        yawQ(g_.sonars[i].yaw_rad));
  add(frame("base_link"), frame("camera_mount"), g_.camera_x_m, g_.camera_y_m, g_.camera_z_m, yawQ(last_.ptz_pan_rad()));
  // Tilt up is positive: a rotation about +y by -tilt; then the optical axes
  // (+z ahead, +x right, +y down) from the mount's (+x ahead, +y left, +z up).
  const Quat optical{0.5, -0.5, 0.5, -0.5};
  add(frame("camera_mount"), frame("camera"), 0, 0, 0, pitchQ(-last_.ptz_tilt_rad()) * optical);
  if (g_.wide_camera)
    add(frame("base_link"), frame("camera_wide"), g_.wide_camera_x_m, g_.wide_camera_y_m, g_.wide_camera_z_m,
        pitchQ(-g_.wide_camera_tilt_deg * std::numbers::pi / 180) * optical);
  return out;
}

void RobotScene::addMap(::foxglove::SceneUpdate& u, uint64_t ns) const {
  // The site map, in the world frame: always sent (empty without a map), so a
  // map that is taken away or changed leaves nothing of the old one drawn.
  auto* walls = entity(u, "map/walls", "map", ns);
  auto* obst = entity(u, "map/obstacles", "map", ns);
  auto* fl = entity(u, "map/floor_lines", "map", ns);
  if (map_) {
    for (const auto& s : map_->walls) addWall(walls, s, kWallHeightM, 0.06, {0.72, 0.72, 0.76, 0.9});
    for (const auto& s : map_->obstacles) addWall(obst, s, kObstacleHeightM, 0.04, {0.55, 0.42, 0.30, 0.95});
    if (!map_->floor_lines.empty()) {
      auto* l = fl->add_lines();
      l->set_type(::foxglove::LinePrimitive::LINE_LIST);
      setPose(l->mutable_pose(), 0, 0, 0.005);
      l->set_thickness(0.03);
      setColor(l->mutable_color(), 0.1, 0.1, 0.1, 1);
      for (const auto& s : map_->floor_lines) {
        addPoint(l, s.a.x, s.a.y, 0);
        addPoint(l, s.b.x, s.b.y, 0);
      }
    }
  }
}

void RobotScene::addBody(::foxglove::SceneUpdate& u, const v1::Telemetry& t, uint64_t ns) const {
  // The robot's body, heading and status, following base_link.
  auto* body = entity(u, "robot/body", frame("base_link"), ns, true);
  auto* cyl = body->add_cylinders();
  setPose(cyl->mutable_pose(), 0, 0, g_.body_height_m / 2);
  setVec(cyl->mutable_size(), 2 * g_.body_radius_m, 2 * g_.body_radius_m, g_.body_height_m);
  cyl->set_bottom_scale(1);
  cyl->set_top_scale(1);
  const bool stopped = t.mode() == v1::ESTOP || t.mode() == v1::FAILSAFE;
  setColor(cyl->mutable_color(), stopped ? 0.85 : 0.15, stopped ? 0.2 : 0.45, stopped ? 0.2 : 0.85, 0.85);
  auto* arrow = body->add_arrows();
  setPose(arrow->mutable_pose(), 0, 0, g_.body_height_m + 0.02);
  arrow->set_shaft_length(g_.body_radius_m);
  arrow->set_shaft_diameter(0.04);
  arrow->set_head_length(0.12);
  arrow->set_head_diameter(0.1);
  setColor(arrow->mutable_color(), 1, 1, 1, 1);
  std::string status = robot_ + " " + v1::Mode_Name(t.mode());
  if (!t.nav_mode().empty()) status += " " + t.nav_mode();
  status += t.has_v_m_s() ? " " + fmt(t.v_m_s()) + " m/s" : " speed unknown";
  if (t.has_speed_factor() && t.speed_factor() < 0.999) status += " x" + fmt(t.speed_factor());
  addText(body, status, 0, 0, g_.body_height_m + 0.35);
}

void RobotScene::addSonars(::foxglove::SceneUpdate& u, const v1::Telemetry& t, uint64_t ns) const {
  // The four sonar beams to their ranges (no echo: a faint cone to the maximum range).
  for (int i = 0; i < 4; ++i) {
    const double r = i < t.ultrasonic_m_size() ? t.ultrasonic_m(i) : -1;
    const bool echo = r >= 0;
    const double range = echo ? std::min(r, g_.sonar_max_m) : g_.sonar_max_m;
    auto* e = entity(u, std::string("robot/") + kSonarNames[static_cast<std::size_t>(i)], frame(kSonarNames[static_cast<std::size_t>(i)]), ns, true);
    auto* tri = e->add_triangles();
    setPose(tri->mutable_pose(), 0, 0, 0);
    const double half = g_.sonar_beam_rad / 2;
    constexpr int kSteps = 6;
    for (int k = 0; k < kSteps; ++k) {
      const double a0 = -half + 2 * half * k / kSteps, a1 = -half + 2 * half * (k + 1) / kSteps;
      addPoint(tri, 0, 0, 0);
      addPoint(tri, range * std::cos(a0), range * std::sin(a0), 0);
      addPoint(tri, range * std::cos(a1), range * std::sin(a1), 0);
    }
    const double near = echo ? std::clamp(1.0 - range / 2.0, 0.0, 1.0) : 0.0;
    setColor(tri->mutable_color(), 0.3 + 0.7 * near, 0.8 - 0.6 * near, 0.3, echo ? 0.35 : 0.08);
    if (echo) addText(e, fmt(r) + " m", range, 0, 0.1, 0.12);
  }
}

void RobotScene::addPeople(::foxglove::SceneUpdate& u, const v1::Telemetry& t, uint64_t ns) const {
  // Tracked people (odometry frame): an upright figure, velocity, pattern, proxemic rings.
  auto* people = entity(u, "people", frame("odom"), ns);
  for (const auto& p : t.people()) {
    const auto col = patternColor(p.pattern());
    auto* c = people->add_cylinders();
    setPose(c->mutable_pose(), p.x_m(), p.y_m(), 0.8);
    setVec(c->mutable_size(), 0.4, 0.3, 1.6);
    c->set_bottom_scale(1);
    c->set_top_scale(0.8);
    setColor(c->mutable_color(), col[0], col[1], col[2], 0.9);
    auto* head = people->add_spheres();
    setPose(head->mutable_pose(), p.x_m(), p.y_m(), 1.75);
    setVec(head->mutable_size(), 0.24, 0.24, 0.26);
    setColor(head->mutable_color(), col[0], col[1], col[2], 0.95);
    const double speed = std::hypot(p.vx_m_s(), p.vy_m_s());
    if (speed > 0.05) {
      auto* a = people->add_arrows();
      setPose(a->mutable_pose(), p.x_m(), p.y_m(), 1.0, yawQ(std::atan2(p.vy_m_s(), p.vx_m_s())));
      a->set_shaft_length(std::min(speed, 2.0));
      a->set_shaft_diameter(0.04);
      a->set_head_length(0.15);
      a->set_head_diameter(0.12);
      setColor(a->mutable_color(), col[0], col[1], col[2], 1);
    }
    std::string label = "person " + std::to_string(p.id()) + " " + fmt(speed) + " m/s";
    if (const auto n = patternName(p.pattern()); !n.empty()) label += " " + n;
    if (p.camera_seen()) label += " (camera)";
    addText(people, label, p.x_m(), p.y_m(), 2.1, 0.15);
    for (std::size_t k = 0; k < kProxemicM.size(); ++k) {
      auto* ring = people->add_lines();
      ring->set_type(::foxglove::LinePrimitive::LINE_LOOP);
      setPose(ring->mutable_pose(), p.x_m(), p.y_m(), 0.02);
      ring->set_thickness(0.02);
      setColor(ring->mutable_color(), col[0], col[1], col[2], k == 0 ? 0.9 : (k == 1 ? 0.6 : 0.3));
      constexpr int kN = 36;
      for (int j = 0; j < kN; ++j) {
        const double a = 2 * std::numbers::pi * j / kN;
        addPoint(ring, kProxemicM[k] * std::cos(a), kProxemicM[k] * std::sin(a), 0);
      }
    }
  }
}

void RobotScene::addCameraPeople(::foxglove::SceneUpdate& u, const v1::Telemetry& t, uint64_t ns) const {
  // Each head's detections of its latest picture (robot frame): a ray along each bearing from
  // the lens, to the feet when the range is known, else dimmed to kBearingRayM. The PTZ head's
  // orange, labelled "camera"; the wide head's cyan, labelled "wide".
  auto* seen = entity(u, "camera_people", frame("base_link"), ns);
  constexpr double kBearingRayM = 8.0;
  const auto rays = [&](const v1::Perception& p, double lens_x, double lens_y, const char* label, double r, double g,
                        double b) {
    for (const auto& s : p.people()) {
      const bool ranged = s.has_range_m();
      const double x1 = ranged ? s.x_m() : lens_x + kBearingRayM * std::cos(s.bearing_rad());
      const double y1 = ranged ? s.y_m() : lens_y + kBearingRayM * std::sin(s.bearing_rad());
      auto* ray = seen->add_lines();
      ray->set_type(::foxglove::LinePrimitive::LINE_STRIP);
      setPose(ray->mutable_pose(), 0, 0, 0.05);
      ray->set_thickness(0.03);
      setColor(ray->mutable_color(), r, g, b, ranged ? 0.9 : 0.45);
      addPoint(ray, lens_x, lens_y, 0);
      addPoint(ray, x1, y1, 0);
      const double deg = s.bearing_rad() * 180 / std::numbers::pi;
      addText(seen, std::string(label) + " " + (deg >= 0 ? "+" : "") + fmt(deg, 0) + " deg" +
                        (ranged ? " " + fmt(s.range_m()) + " m" : ""),
              x1, y1, 0.3, 0.14);
    }
  };
  if (t.has_perception()) rays(t.perception(), g_.camera_x_m, g_.camera_y_m, "camera", 1.0, 0.55, 0.1);
  if (t.has_wide_perception())
    rays(t.wide_perception(), g_.wide_camera_x_m, g_.wide_camera_y_m, "wide", 0.1, 0.8, 0.9);
}

void RobotScene::addRoute(::foxglove::SceneUpdate& u, const v1::Telemetry& t, uint64_t ns) const {
  // The route and its goals (odometry frame), labelled; reached goals dimmed.
  auto* route = entity(u, "route", frame("odom"), ns);
  if (!route_.empty()) {
    const bool navigating = t.mode() == v1::NAVIGATING;
    const uint32_t current = navigating ? t.goal_index() : static_cast<uint32_t>(route_.size());
    auto* line = route->add_lines();
    line->set_type(::foxglove::LinePrimitive::LINE_STRIP);
    setPose(line->mutable_pose(), 0, 0, 0.03);
    line->set_thickness(0.03);
    setColor(line->mutable_color(), 0.2, 0.9, 0.9, 0.8);
    for (const auto& g : route_) addPoint(line, g.x_m(), g.y_m(), 0);
    for (std::size_t i = 0; i < route_.size(); ++i) {
      const auto& g = route_[i];
      const bool reached = i < current;
      auto* s = route->add_spheres();
      setPose(s->mutable_pose(), g.x_m(), g.y_m(), 0.1);
      setVec(s->mutable_size(), 0.2, 0.2, 0.2);
      if (i == current) setColor(s->mutable_color(), 1, 1, 0.2, 1);
      else setColor(s->mutable_color(), 0.2, 0.9, 0.9, reached ? 0.35 : 0.9);
      std::string label = std::to_string(i + 1);
      if (!g.label().empty()) label += " " + g.label();
      if (g.dwell_s() > 0) label += " (" + fmt(g.dwell_s(), 0) + " s)";
      addText(route, label, g.x_m(), g.y_m(), 0.4, 0.15);
    }
  }
}

void RobotScene::addAlarms(::foxglove::SceneUpdate& u, uint64_t ns) const {
  // Gas alarms where they were raised (odometry frame): red while raised, grey once cleared.
  auto* alarms = entity(u, "gas/alarms", frame("odom"), ns);
  for (const auto& [id, a] : alarms_) {
    if (!a.alarm.has_pose()) continue;
    const double x = a.alarm.pose().x_m(), y = a.alarm.pose().y_m();
    const bool high = a.alarm.level() == v1::GasAlarm::HIGH;
    auto* s = alarms->add_cylinders();
    setPose(s->mutable_pose(), x, y, 1.0);
    setVec(s->mutable_size(), 0.15, 0.15, 2.0);
    s->set_bottom_scale(1);
    s->set_top_scale(1);
    if (!a.active) setColor(s->mutable_color(), 0.6, 0.6, 0.6, 0.5);
    else if (high) setColor(s->mutable_color(), 1, 0.1, 0.1, 0.9);
    else setColor(s->mutable_color(), 1, 0.6, 0.1, 0.9);
    std::string text = a.alarm.channel_name() + " " + v1::GasAlarm::Level_Name(a.alarm.level());
    if (a.alarm.level() != v1::GasAlarm::SENSOR_FAULT)
      text += " " + fmt(a.alarm.value(), 1) + " " + a.alarm.unit();
    if (!a.active) text += " (cleared)";
    addText(alarms, text, x, y, 2.2, 0.16);
  }
}

::foxglove::SceneUpdate RobotScene::scene(uint64_t ns) const {
  ::foxglove::SceneUpdate u;
  addMap(u, ns);
  if (!have_telemetry_) return u;
  const auto& t = last_;
  addBody(u, t, ns);
  addSonars(u, t, ns);
  addPeople(u, t, ns);
  addCameraPeople(u, t, ns);
  addRoute(u, t, ns);
  addAlarms(u, ns);
  return u;
}

std::vector<std::string> RobotScene::gridChannels() const {
  std::vector<std::string> out;
  for (const auto& ch : channels_)
    if (!ch.map.empty()) out.push_back(ch.info.name());
  return out;
}

std::optional<::foxglove::Grid> RobotScene::grid(const std::string& channel, uint64_t ns) const {
  const auto it = std::find_if(channels_.begin(), channels_.end(), [&](const Channel& c) { return c.info.name() == channel; });
  if (it == channels_.end() || it->map.empty()) return std::nullopt;
  const auto& m = it->map;
  ::foxglove::Grid g;
  setTime(g.mutable_timestamp(), ns);
  g.set_frame_id(frame("odom"));
  setPose(g.mutable_pose(), m.originX(), m.originY(), 0.01);
  g.set_column_count(static_cast<uint32_t>(m.cols()));
  g.mutable_cell_size()->set_x(m.cellM());
  g.mutable_cell_size()->set_y(m.cellM());
  constexpr uint32_t kCell = 8;  // float32 value, then red, green, blue, alpha
  g.set_cell_stride(kCell);
  g.set_row_stride(static_cast<uint32_t>(m.cols()) * kCell);
  const auto field = [&](const char* name, uint32_t offset, ::foxglove::PackedElementField::NumericType type) {
    auto* f = g.add_fields();
    f->set_name(name);
    f->set_offset(offset);
    f->set_type(type);
  };
  field("value", 0, ::foxglove::PackedElementField::FLOAT32);
  field("red", 4, ::foxglove::PackedElementField::UINT8);
  field("green", 5, ::foxglove::PackedElementField::UINT8);
  field("blue", 6, ::foxglove::PackedElementField::UINT8);
  field("alpha", 7, ::foxglove::PackedElementField::UINT8);
  std::string data(m.cols() * m.rows() * kCell, '\0');
  for (std::size_t r = 0; r < m.rows(); ++r)
    for (std::size_t c = 0; c < m.cols(); ++c) {
      char* cell = data.data() + (r * m.cols() + c) * kCell;
      const double v = m.value(c, r);
      const float f = static_cast<float>(v);
      std::memcpy(cell, &f, 4);  // little-endian hosts (x86-64, arm64)
      if (!std::isfinite(v)) continue;  // alpha 0: no data
      const auto rgb = gasColor(v, it->info);
      cell[4] = static_cast<char>(rgb[0]);
      cell[5] = static_cast<char>(rgb[1]);
      cell[6] = static_cast<char>(rgb[2]);
      cell[7] = static_cast<char>(static_cast<uint8_t>(std::lround(60 + 150 * m.coverage(c, r))));
    }
  g.set_data(std::move(data));
  return g;
}

::foxglove::CompressedVideo RobotScene::cameraFrame(const std::string& robot, const video::Frame& f, uint64_t ns,
                                                   v1::CameraHead head) {
  ::foxglove::CompressedVideo v;
  setTime(v.mutable_timestamp(), ns);
  v.set_frame_id(robot + (head == v1::WIDE_HEAD ? "/camera_wide" : "/camera"));
  v.set_data(f.annexb.data(), f.annexb.size());
  v.set_format("h264");
  return v;
}

::foxglove::Log RobotScene::log(const std::string& robot, const v1::Event& e, uint64_t ns) {
  ::foxglove::Log l;
  setTime(l.mutable_timestamp(), ns);
  l.set_name(robot);
  l.set_message(e.text());
  auto level = ::foxglove::Log::INFO;
  switch (e.kind()) {
    case v1::Event::FAULT_RAISED: level = ::foxglove::Log::ERROR; break;
    case v1::Event::ALARM_RAISED:
      level = e.gas_alarm().level() == v1::GasAlarm::HIGH ? ::foxglove::Log::ERROR : ::foxglove::Log::WARNING;
      break;
    default: break;
  }
  l.set_level(level);
  return l;
}

}  // namespace inspect::server::scene
