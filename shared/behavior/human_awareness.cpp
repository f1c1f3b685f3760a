#include "shared/util/number_text.hpp"
#include "shared/behavior/human_awareness.hpp"

#include <sys/stat.h>

#include <cmath>
#include <stdexcept>

namespace inspect::behavior {

const char* toString(SpeedPolicy p) {
  switch (p) {
    case SpeedPolicy::kFuzzy: return "fuzzy";
    case SpeedPolicy::kNone: return "none";
    case SpeedPolicy::kStopAndWait: return "stop_and_wait";
    case SpeedPolicy::kFuzzyNoPattern: return "fuzzy_no_pattern";
  }
  return "?";
}

SpeedPolicy parseSpeedPolicy(const std::string& s) {
  if (s == "fuzzy") return SpeedPolicy::kFuzzy;
  if (s == "none") return SpeedPolicy::kNone;
  if (s == "stop_and_wait") return SpeedPolicy::kStopAndWait;
  if (s == "fuzzy_no_pattern") return SpeedPolicy::kFuzzyNoPattern;
  throw std::invalid_argument("unknown speed policy '" + s + "' (fuzzy, none, stop_and_wait or fuzzy_no_pattern)");
}

HumanAwareness::HumanAwareness(const config::UltrasonicConfig& sonar, const AwarenessConfig& cfg,
                               SpeedStrategy strategy, std::vector<geometry::Segment> map)
    : cfg_(cfg), tracker_(sonar, cfg.tracker, map), classifier_(cfg.pattern), strategy_(std::move(strategy)) {
  walls_.reserve(map.size());
  for (const auto& m : map) walls_.push_back({m});
}

const Awareness& HumanAwareness::step(const control::Pose2& pose, const std::array<double, 4>& ranges_m, double t_s) {
  const double dt = last_t_s_ < 0 ? 0.0 : std::max(0.0, t_s - last_t_s_);
  last_t_s_ = t_s;
  tracker_.step(pose, ranges_m, t_s);
  if (dt > 0) {  // the robot's own velocity, for the person's range rate
    constexpr double kAlpha = 0.2;
    robot_vx_ += kAlpha * ((pose.x_m - last_pose_.x_m) / dt - robot_vx_);
    robot_vy_ += kAlpha * ((pose.y_m - last_pose_.y_m) / dt - robot_vy_);
  }
  last_pose_ = pose;
  Awareness a;
  int people = 0;
  for (const auto& t : tracker_.tracks()) people += t.isPerson() ? 1 : 0;
  a.people = people;
  if (const HumanTrack* n = tracker_.nearest(pose)) {
    a.person = true;
    a.distance_m = std::hypot(n->x[0] - pose.x_m, n->x[1] - pose.y_m);
    a.person_speed_m_s = n->speed();
    a.pattern = classifier_.step(pose, n->x[0], n->x[1], n->x[2], n->x[3], dt);
    const double rx = n->x[0] - pose.x_m, ry = n->x[1] - pose.y_m;
    const double d = std::max(std::hypot(rx, ry), 1e-6);
    a.range_rate_m_s = (rx * (n->x[2] - robot_vx_) + ry * (n->x[3] - robot_vy_)) / d;
    const double ahead = rx * std::cos(pose.theta_rad) + ry * std::sin(pose.theta_rad);
    a.passing = ahead < cfg_.passing_ahead_m && a.range_rate_m_s > cfg_.passing_rate_m_s;
    predict(pose, *n, a);
  } else {
    a.pattern = classifier_.stepNone(dt);
  }
  // What the policy is given: the tracked nearest person, or the override.
  bool person = a.person, passing = a.passing;
  double distance = a.anticipating ? std::min(a.distance_m, a.predicted_min_m) : a.distance_m;
  double speed = a.person_speed_m_s;
  Pattern pattern = a.pattern;
  const bool overridden = override_.has_value();  // the truth's "none" means nobody to react to
  if (override_) {
    person = override_->person;
    passing = false;
    distance = override_->distance_m;
    speed = override_->speed_m_s;
    pattern = override_->pattern;
    override_.reset();
  }
  // A person without a settled pattern still slows the robot as the most
  // cautious pattern would (crossing/confronting share the cautious ramp).
  const SpeedPolicy policy = cfg_.enabled ? cfg_.policy : SpeedPolicy::kNone;
  Pattern for_speed = person && pattern == Pattern::kNone && !overridden ? Pattern::kConfronting : pattern;
  if (policy == SpeedPolicy::kFuzzyNoPattern) for_speed = Pattern::kConfronting;
  if (!person || policy == SpeedPolicy::kNone) {
    a.target_factor = 1.0;
  } else if (policy == SpeedPolicy::kStopAndWait) {
    a.target_factor = distance < cfg_.speed.max_avoidance_m ? 0.0 : 1.0;
  } else if (passing) {
    a.target_factor = 1.0;  // beside or behind and moving away: no longer interfering
  } else {
    a.target_factor = strategy_.speedFactor(distance, speed, for_speed);  // Eq 9
  }
  // Rate limit (no speed steps); the first tick takes the target as it is.
  a.speed_factor = a.target_factor;
  if (dt > 0) {
    const double prev = last_.speed_factor;
    if (cfg_.factor_fall_per_s > 0) a.speed_factor = std::max(a.speed_factor, prev - cfg_.factor_fall_per_s * dt);
    if (cfg_.factor_rise_per_s > 0) a.speed_factor = std::min(a.speed_factor, prev + cfg_.factor_rise_per_s * dt);
  }
  last_ = a;
  return last_;
}

void HumanAwareness::predict(const control::Pose2& pose, const HumanTrack& n, Awareness& a) {
  constexpr double kStep_s = 0.1;
  const auto steps = static_cast<std::size_t>(std::clamp(cfg_.predict_horizon_s / kStep_s, 0.0,
                                                         static_cast<double>(predicted_.size())));
  if (steps == 0) return;
  Agent person;
  person.position_m = {n.x[0], n.x[1]};
  person.velocity_m_s = {n.x[2], n.x[3]};
  person.radius_m = 0.25;
  Agent robot;
  robot.position_m = {pose.x_m, pose.y_m};
  robot.velocity_m_s = {robot_vx_, robot_vy_};
  robot.radius_m = cfg_.robot_radius_m;
  // Eq 7 prediction of the person (walls from the map, the robot keeping its velocity).
  const std::size_t k_n = predictPath(person, &robot, walls_, cfg_.social_force, kStep_s,
                                      std::span<Eigen::Vector2d>(predicted_.data(), steps));
  double best = -1.0, best_t = 0.0;
  for (std::size_t k = 0; k < k_n; ++k) {
    const double t = kStep_s * static_cast<double>(k + 1);
    const Eigen::Vector2d r = robot.position_m + robot.velocity_m_s * t;
    const double d = (predicted_[k] - r).norm();
    if (best < 0 || d < best) {
      best = d;
      best_t = t;
    }
  }
  if (best < 0) return;
  a.predicted_min_m = best;
  a.predicted_at_s = best_t;
  // Eq 8: what is left of the robot's avoidance distance when it gets there.
  a.avoid_m = avoidanceDistance(cfg_.speed.max_avoidance_m, std::hypot(robot_vx_, robot_vy_), best_t);
  a.anticipating = best < a.distance_m && best < a.avoid_m;
}

namespace {
// A recall-by-distance table of `tracker.camera` (<prefix>recall_upto_m and
// <prefix>recall, both or neither): distances rising, recalls within [0, 1].
void readRecallTable(const config::ConfigNode& n, const std::string& prefix, RecallTable& t) {
  const std::string upto_key = prefix + "recall_upto_m", recall_key = prefix + "recall";
  if (!n.has(upto_key) && !n.has(recall_key)) return;
  const auto upto = n.numbers(upto_key, static_cast<int>(t.upto_m.size()));
  const auto recall = n.numbers(recall_key, static_cast<int>(t.recall.size()));
  for (std::size_t i = 0; i < upto.size(); ++i) {
    if (i > 0 && !(upto[i] > upto[i - 1])) n.fail(upto_key, "distances must rise");
    if (!(recall[i] >= 0 && recall[i] <= 1)) n.fail(recall_key, "each recall must be within [0, 1]");
    t.upto_m[i] = upto[i];
    t.recall[i] = recall[i];
  }
}

CameraFusionParams readCameraFusion(const config::ConfigNode& n) {
  CameraFusionParams c;
  c.enabled = n.boolean("enabled", c.enabled);
  c.bearing_sigma_deg = n.number("bearing_sigma_deg", c.bearing_sigma_deg, 0.01, 20);
  c.range_sigma_frac = n.number("range_sigma_frac", c.range_sigma_frac, 0.01, 2);
  c.range_bias_frac = n.number("range_bias_frac", c.range_bias_frac, -0.5, 1);
  c.gate_chi2 = n.number("gate_chi2", c.gate_chi2, 1, 100);
  c.hit_logodds = n.number("hit_logodds", c.hit_logodds, 0, 10);
  c.person_logodds = n.number("person_logodds", c.person_logodds, 0, 10);
  c.deny_logodds = n.number("deny_logodds", c.deny_logodds, -10, 0);
  c.doubt_logodds = n.number("doubt_logodds", c.doubt_logodds, -10, 0);
  c.max_logodds = n.number("max_logodds", c.max_logodds, 1, 20);
  c.confirm_hits = static_cast<int>(n.integer("confirm_hits", c.confirm_hits, 1, 100));
  c.bearing_hold_s = n.number("bearing_hold_s", c.bearing_hold_s, 0, 10);
  c.max_new_range_m = n.number("max_new_range_m", c.max_new_range_m, 0, 50);
  c.edge_margin_deg = n.number("edge_margin_deg", c.edge_margin_deg, 0, 30);
  c.occluder_width_m = n.number("occluder_width_m", c.occluder_width_m, 0, 3);
  readRecallTable(n, "", c.recall);
  readRecallTable(n, "wide_", c.wide_recall);
  if (!(c.deny_logodds < c.person_logodds)) n.fail("deny_logodds", "must be below person_logodds");
  if (!(c.deny_logodds <= c.doubt_logodds)) n.fail("doubt_logodds", "must be at or above deny_logodds");
  return c;
}
}  // namespace

AwarenessConfig loadAwarenessConfig(const config::ConfigNode& root, const std::string& base_dir) {
  AwarenessConfig c;
  const auto a = root.optChild("awareness");
  c.enabled = a.boolean("enabled", c.enabled);
  if (a.has("policy")) {
    try {
      c.policy = parseSpeedPolicy(a.string("policy", "fuzzy"));
    } catch (const std::invalid_argument& e) {
      a.fail("policy", e.what());
    }
  }
  c.speed_fis = a.string("speed_fis", c.speed_fis);
  struct stat st {};
  if (!c.speed_fis.empty() && c.speed_fis[0] != '/' && ::stat(c.speed_fis.c_str(), &st) != 0) {
    const std::string alt = base_dir + "/../" + c.speed_fis;
    if (::stat(alt.c_str(), &st) == 0) c.speed_fis = alt;
  }
  c.factor_fall_per_s = a.number("factor_fall_per_s", c.factor_fall_per_s, 0, 100);
  c.factor_rise_per_s = a.number("factor_rise_per_s", c.factor_rise_per_s, 0, 100);
  c.passing_ahead_m = a.number("passing_ahead_m", c.passing_ahead_m, -5, 5);
  c.passing_rate_m_s = a.number("passing_rate_m_s", c.passing_rate_m_s, 0, 5);
  c.predict_horizon_s = a.number("predict_horizon_s", c.predict_horizon_s, 0, 6.4);
  c.speed.max_avoidance_m = a.number("max_avoidance_m", c.speed.max_avoidance_m, 0.5, 10.0);
  c.speed.sensitive_m = a.number("sensitive_m", c.speed.sensitive_m, 0.1, 5.0);
  if (!(c.speed.sensitive_m < c.speed.max_avoidance_m))
    a.fail("sensitive_m", "must be below max_avoidance_m (" + util::fmtShort(c.speed.max_avoidance_m) +
                              " m): the stop zone lies inside the avoidance distance");
  const auto t = root.optChild("tracker");
  c.tracker.gate_m = t.number("gate_m", c.tracker.gate_m, 0.1, 5);
  c.tracker.map_margin_m = t.number("map_margin_m", c.tracker.map_margin_m, 0, 2);
  c.tracker.confirm_hits = static_cast<int>(t.integer("confirm_hits", c.tracker.confirm_hits, 1, 100));
  c.tracker.confirm_window_s = t.number("confirm_window_s", c.tracker.confirm_window_s, 0.05, 10);
  c.tracker.coast_s = t.number("coast_s", c.tracker.coast_s, 0.05, 10);
  c.tracker.min_person_speed_m_s = t.number("min_person_speed_m_s", c.tracker.min_person_speed_m_s, 0, 2);
  c.tracker.static_after_s = t.number("static_after_s", c.tracker.static_after_s, 0.1, 60);
  c.tracker.person_hold_s = t.number("person_hold_s", c.tracker.person_hold_s, 0.1, 3600);
  c.tracker.moving_for_s = t.number("moving_for_s", c.tracker.moving_for_s, 0, 10);
  c.tracker.grid_static_s = t.number("grid_static_s", c.tracker.grid_static_s, 0.1, 60);
  c.tracker.triangulate_front = t.boolean("triangulate_front", c.tracker.triangulate_front);
  c.tracker.wall_trace = t.boolean("wall_trace", c.tracker.wall_trace);
  c.tracker.new_track_margin_m = t.number("new_track_margin_m", c.tracker.new_track_margin_m, 0, 5);
  c.tracker.camera = readCameraFusion(t.optChild("camera"));
  c.social_force = readSocialForceParams(root.optChild("social_force"));
  const auto p = root.optChild("pattern");
  c.pattern.min_speed_m_s = p.number("min_speed_m_s", c.pattern.min_speed_m_s, 0, 2);
  c.pattern.crossing_deg = p.number("crossing_deg", c.pattern.crossing_deg, 20, 90);
  c.pattern.along_deg = p.number("along_deg", c.pattern.along_deg, 0, 45);
  c.pattern.confront_lateral_m = p.number("confront_lateral_m", c.pattern.confront_lateral_m, 0, 5);
  c.pattern.max_lateral_m = p.number("max_lateral_m", c.pattern.max_lateral_m, 0, 10);
  c.pattern.dwell_s = p.number("dwell_s", c.pattern.dwell_s, 0, 5);
  if (c.pattern.along_deg >= c.pattern.crossing_deg) p.fail("along_deg", "must be below crossing_deg (the gap is the hysteresis band)");
  const auto al = root.optChild("active_look");
  auto& l = c.active_look;
  l.enabled = al.boolean("enabled", l.enabled);
  l.min_off_axis_deg = al.number("min_off_axis_deg", l.min_off_axis_deg, 0, 180);
  l.max_pan_deg = al.number("max_pan_deg", l.max_pan_deg, 0, 180);
  l.dwell_s = al.number("dwell_s", l.dwell_s, 0.1, 10);
  l.slew_deg_s = al.number("slew_deg_s", l.slew_deg_s, 1, 2000);
  l.revisit_s = al.number("revisit_s", l.revisit_s, 0, 600);
  l.ahead_m = al.number("ahead_m", l.ahead_m, 0, 20);
  l.ahead_deg = al.number("ahead_deg", l.ahead_deg, 0, 90);
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
