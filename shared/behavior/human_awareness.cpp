#include "shared/behavior/human_awareness.hpp"

#include <sys/stat.h>

#include <cmath>

namespace inspect::behavior {

HumanAwareness::HumanAwareness(const config::UltrasonicConfig& sonar, const AwarenessConfig& cfg,
                               SpeedStrategy strategy, std::vector<MapSegment> map)
    : cfg_(cfg), tracker_(sonar, cfg.tracker, std::move(map)), classifier_(cfg.pattern), strategy_(std::move(strategy)) {}

const Awareness& HumanAwareness::step(const control::Pose2& pose, const std::array<double, 4>& ranges_m, double t_s) {
  const double dt = last_t_s_ < 0 ? 0.0 : std::max(0.0, t_s - last_t_s_);
  last_t_s_ = t_s;
  tracker_.step(pose, ranges_m, t_s);
  Awareness a;
  int people = 0;
  for (const auto& t : tracker_.tracks()) people += t.isPerson() ? 1 : 0;
  a.people = people;
  if (const HumanTrack* n = tracker_.nearest(pose)) {
    a.person = true;
    a.distance_m = std::hypot(n->x[0] - pose.x_m, n->x[1] - pose.y_m);
    a.person_speed_m_s = n->speed();
    a.pattern = classifier_.step(pose, n->x[0], n->x[1], n->x[2], n->x[3], dt);
  } else {
    a.pattern = classifier_.stepNone(dt);
  }
  // A person without a settled pattern still slows the robot as the most
  // cautious pattern would (crossing/confronting share the cautious ramp).
  const Pattern for_speed = a.person && a.pattern == Pattern::kNone ? Pattern::kConfronting : a.pattern;
  a.speed_factor = !cfg_.enabled || !a.person ? 1.0 : strategy_.speedFactor(a.distance_m, a.person_speed_m_s, for_speed);
  last_ = a;
  return last_;
}

AwarenessConfig loadAwarenessConfig(const config::ConfigNode& root, const std::string& base_dir) {
  AwarenessConfig c;
  const auto a = root.optChild("awareness");
  c.enabled = a.boolean("enabled", c.enabled);
  c.speed_fis = a.string("speed_fis", c.speed_fis);
  struct stat st {};
  if (!c.speed_fis.empty() && c.speed_fis[0] != '/' && ::stat(c.speed_fis.c_str(), &st) != 0) {
    const std::string alt = base_dir + "/../" + c.speed_fis;
    if (::stat(alt.c_str(), &st) == 0) c.speed_fis = alt;
  }
  c.speed.max_avoidance_m = a.number("max_avoidance_m", c.speed.max_avoidance_m, 0.5, 10.0);
  c.speed.sensitive_m = a.number("sensitive_m", c.speed.sensitive_m, 0.1, 5.0);
  const auto t = root.optChild("tracker");
  c.tracker.gate_m = t.number("gate_m", c.tracker.gate_m, 0.1, 5);
  c.tracker.map_margin_m = t.number("map_margin_m", c.tracker.map_margin_m, 0, 2);
  c.tracker.confirm_hits = static_cast<int>(t.integer("confirm_hits", c.tracker.confirm_hits, 1, 100));
  c.tracker.confirm_window_s = t.number("confirm_window_s", c.tracker.confirm_window_s, 0.05, 10);
  c.tracker.coast_s = t.number("coast_s", c.tracker.coast_s, 0.05, 10);
  c.tracker.min_person_speed_m_s = t.number("min_person_speed_m_s", c.tracker.min_person_speed_m_s, 0, 2);
  c.tracker.static_after_s = t.number("static_after_s", c.tracker.static_after_s, 0.1, 60);
  c.tracker.moving_for_s = t.number("moving_for_s", c.tracker.moving_for_s, 0, 10);
  c.tracker.grid_static_s = t.number("grid_static_s", c.tracker.grid_static_s, 0.1, 60);
  const auto p = root.optChild("pattern");
  c.pattern.min_speed_m_s = p.number("min_speed_m_s", c.pattern.min_speed_m_s, 0, 2);
  c.pattern.crossing_deg = p.number("crossing_deg", c.pattern.crossing_deg, 45, 90);
  c.pattern.along_deg = p.number("along_deg", c.pattern.along_deg, 0, 45);
  c.pattern.confront_lateral_m = p.number("confront_lateral_m", c.pattern.confront_lateral_m, 0, 5);
  c.pattern.max_lateral_m = p.number("max_lateral_m", c.pattern.max_lateral_m, 0, 10);
  c.pattern.dwell_s = p.number("dwell_s", c.pattern.dwell_s, 0, 5);
  if (c.pattern.along_deg >= c.pattern.crossing_deg) p.fail("along_deg", "must be below crossing_deg (the gap is the hysteresis band)");
  validate(c.speed);
  return c;
}

AwarenessConfig loadAwarenessConfigFile(const std::string& path) {
  const auto root = config::ConfigNode::loadFile(path);
  const auto slash = path.rfind('/');
  AwarenessConfig c = loadAwarenessConfig(root, slash == std::string::npos ? "." : path.substr(0, slash));
  root.checkKnown();
  return c;
}

}  // namespace inspect::behavior
