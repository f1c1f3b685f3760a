#include "experiments/scenarios/scenario.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include "inspect_robot/v1/link.pb.h"
#include "shared/robot/awareness.hpp"
#include "shared/robot/robot_core.hpp"
#include "shared/world/robot_map.hpp"
#include "shared/behavior/pattern_classifier.hpp"
#include "shared/behavior/speed_strategy.hpp"
#include "shared/serial/frame_codec.hpp"
#include "sim/simulation.hpp"

namespace inspect::sim {
namespace {

constexpr double kIntimate_m = 0.45;  // Hall: intimate zone
constexpr double kPersonal_m = 1.2;   // Hall: end of the personal zone
constexpr double kStopSpeed_m_s = 0.02;
constexpr double kMovingSpeed_m_s = 0.1;
constexpr double kCommandTime_s = 0.02;  // the command goes out after the first sensor frame
constexpr double kJerkSample_s = 0.1;    // jerk from the speed sampled at the paper's 0.1 s
constexpr double kJerkSkip_s = 3.0;      // ...after the start-up (the same for every policy)

behavior::Pattern patternByName(const config::ConfigNode& n, const std::string& key) {
  const std::string s = n.oneOf(key, "none", {"none", "crossing", "encountering", "leading", "confronting"});
  for (int i = 0; i <= 4; ++i)
    if (behavior::toString(static_cast<behavior::Pattern>(i)) == s) return static_cast<behavior::Pattern>(i);
  return behavior::Pattern::kNone;
}

ScenarioTask readTask(const config::ConfigNode& n) {
  ScenarioTask t;
  const std::string kind = n.oneOf("kind", "", {"line", "circle", "goto"});
  t.speed_m_s = n.number("speed_m_s", 0.5, 0.05, 1.0);
  t.controller = n.oneOf("controller", "", {"", "direct", "pid", "fuzzy_pid"});
  if (kind == "line") {
    t.kind = ScenarioTask::Kind::kLine;
    t.length_m = n.requireNumber("length_m", 0.1, 1000);
  } else if (kind == "circle") {
    t.kind = ScenarioTask::Kind::kCircle;
    t.radius_m = n.requireNumber("radius_m", -100, 100);
    if (std::abs(t.radius_m) < 0.1) n.fail("radius_m", "must be at least 0.1 m in magnitude");
    t.laps = n.number("laps", 1.0, 0.01, 100);
  } else {
    t.kind = ScenarioTask::Kind::kGoTo;
    const auto xy = n.numbers("points_m");
    if (xy.empty() || xy.size() % 2 != 0) n.fail("points_m", "needs pairs x, y (at least one point)");
    for (std::size_t i = 0; i + 1 < xy.size(); i += 2) t.points_m.emplace_back(xy[i], xy[i + 1]);
  }
  return t;
}

std::optional<double> optSeconds(const config::ConfigNode& n, const std::string& key) {
  if (!n.has(key)) return std::nullopt;
  return n.number(key, 0, 0, 1000);
}

// True when some part of a person's body is inside a sonar cone within range.
bool inSomeCone(const config::UltrasonicConfig& u, const control::Pose2& pose, const behavior::Agent& a) {
  for (const auto& m : u.mounts) {
    const control::Pose2 sensor = config::mountPose(pose, m);
    const double dx = a.position_m.x() - sensor.x_m, dy = a.position_m.y() - sensor.y_m, d = std::hypot(dx, dy);
    if (d - a.radius_m > u.max_range_m) continue;
    const double bearing = std::remainder(std::atan2(dy, dx) - sensor.theta_rad, 2 * M_PI);
    const double size = d > a.radius_m ? std::asin(a.radius_m / d) : M_PI;
    if (std::abs(bearing) - size < u.beam_width_rad / 2) return true;
  }
  return false;
}

// Ground-truth pattern of a person, by the same definitions as the robot's classifier.
struct TruthPattern {
  behavior::PatternClassifier classifier;
  behavior::Pattern step(const control::Pose2& robot, const behavior::Agent* a, double dt) {
    if (!a) return classifier.stepNone(dt);
    return classifier.step(robot, a->position_m.x(), a->position_m.y(), a->velocity_m_s.x(), a->velocity_m_s.y(), dt);
  }
};

/// The scenario's task as the robot's command (id 1).
v1::Command taskCommand(const ScenarioSpec& spec) {
  v1::Command cmd;
  cmd.set_id(1);
  switch (spec.task.kind) {
    case ScenarioTask::Kind::kLine: {
      auto* t = cmd.mutable_track();
      t->mutable_line()->set_length_m(spec.task.length_m);
      t->mutable_line()->set_speed_m_s(spec.task.speed_m_s);
      t->set_controller(spec.task.controller);
      break;
    }
    case ScenarioTask::Kind::kCircle: {
      auto* t = cmd.mutable_track();
      t->mutable_circle()->set_radius_m(spec.task.radius_m);
      t->mutable_circle()->set_speed_m_s(spec.task.speed_m_s);
      t->mutable_circle()->set_laps(spec.task.laps);
      t->set_controller(spec.task.controller);
      break;
    }
    case ScenarioTask::Kind::kGoTo: {
      auto* g = cmd.mutable_go_to();
      for (const auto& [x, y] : spec.task.points_m) {
        auto* p = g->add_points();
        p->set_x_m(x);
        p->set_y_m(y);
      }
      g->set_speed_m_s(spec.task.speed_m_s);
      g->set_name(spec.name);
      break;
    }
  }
  return cmd;
}

/// What the simulation's truth says tick by tick (docs/scenarios.md): path,
/// speed, stop and slowest point, jerk, the nearest person and the zones,
/// the true against the reported pattern; and the series when kept.
struct TruthTally {
  explicit TruthTally(const behavior::AwarenessConfig& acfg, const control::Pose2& start)
      : truth{behavior::PatternClassifier(acfg.pattern)}, last_pose(start) {}
  TruthPattern truth;
  std::array<uint64_t, 5> pattern_counts{};
  uint64_t pattern_ticks = 0, pattern_hits = 0;
  bool moved = false;
  control::Pose2 last_pose;
  double jerk_v[3] = {0, 0, 0};
  int jerk_n = 0;
  double next_jerk_t = 0.0;
  std::map<std::size_t, std::size_t> person_index;  // crowd index -> people_paths index
  double next_person_t = 0.0;
  behavior::Pattern last_pattern = behavior::Pattern::kNone;

  /// One tick at `t` (after the core's): into run's metrics (and series).
  void tick(ScenarioRun& run, const Simulation& sim, const behavior::HumanAwareness& awareness,
            const ScenarioContext& ctx, const RunOptions& opt, double avoid_m, double t);
};

void TruthTally::tick(ScenarioRun& run, const Simulation& sim, const behavior::HumanAwareness& awareness,
                      const ScenarioContext& ctx, const RunOptions& opt, double avoid_m, double t) {
  RunMetrics& m = run.metrics;
  const double body = ctx.robot.geometry.body_radius_m;
  const auto& crowd = sim.pedestrians();
  const auto& st = sim.state();
  m.path_length_m += std::hypot(st.pose.x_m - last_pose.x_m, st.pose.y_m - last_pose.y_m);
  last_pose = st.pose;
  const double v = 0.5 * ctx.robot.geometry.wheel_radius_m * (st.wheel.left_rad_s + st.wheel.right_rad_s);
  if (std::abs(v) > kMovingSpeed_m_s) moved = true;
  if (moved && m.stop_s < 0 && m.detect_s >= 0 && std::abs(v) < kStopSpeed_m_s) m.stop_s = t;
  if (moved && m.detect_s >= 0 && !m.completed && (m.slowest_m_s < 0 || std::abs(v) < m.slowest_m_s)) {
    m.slowest_m_s = std::abs(v);
    m.slowest_s = t;
  }
  if (t >= next_jerk_t) {  // speed every 0.1 s -> acceleration -> jerk
    next_jerk_t += kJerkSample_s;
    jerk_v[0] = jerk_v[1];
    jerk_v[1] = jerk_v[2];
    jerk_v[2] = v;
    if (++jerk_n >= 3) {
      const double j = (jerk_v[2] - 2 * jerk_v[1] + jerk_v[0]) / (kJerkSample_s * kJerkSample_s);
      if (t > kJerkSkip_s) m.max_jerk_m_s3 = std::max(m.max_jerk_m_s3, std::abs(j));
    }
  }
  const behavior::Agent* nearest = nullptr;
  double nearest_m = -1, nearest_gap = -1;
  for (std::size_t i = 0; i < crowd.size(); ++i) {
    if (!crowd.present(i)) continue;
    const auto& a = crowd.agent(i);
    const double d = std::hypot(a.position_m.x() - st.pose.x_m, a.position_m.y() - st.pose.y_m);
    if (nearest_m < 0 || d < nearest_m) {
      nearest_m = d;
      nearest_gap = d - body - a.radius_m;
      nearest = &a;
    }
    if (opt.keep_series && t >= next_person_t) {
      auto it = person_index.find(i);
      if (it == person_index.end()) {
        it = person_index.emplace(i, run.people_paths.size()).first;
        run.people_paths.push_back({std::string(crowd.script(i).id), {}, {}, {}});
      }
      auto& pp = run.people_paths[it->second];
      pp.t_s.push_back(t);
      pp.x_m.push_back(a.position_m.x());
      pp.y_m.push_back(a.position_m.y());
    }
  }
  if (opt.keep_series && t >= next_person_t) next_person_t += 0.1;
  if (nearest) {
    if (m.min_person_m < 0 || nearest_m < m.min_person_m) m.min_person_m = nearest_m;
    if (m.min_gap_m < 0 || nearest_gap < m.min_gap_m) m.min_gap_m = nearest_gap;
    if (nearest_m < kIntimate_m) m.intimate_s += 0.01;
    if (nearest_m < kPersonal_m) m.personal_s += 0.01;
    if (m.enter_avoidance_s < 0 && nearest_m < avoid_m) m.enter_avoidance_s = t;
  }
  const behavior::Pattern tp = truth.step(st.pose, nearest && nearest_m < avoid_m ? nearest : nullptr, 0.01);
  const auto& a = awareness.last();
  if (a.person && m.detect_s < 0) m.detect_s = t;
  m.min_speed_factor = std::min(m.min_speed_factor, a.speed_factor);
  if (a.pattern != last_pattern) {
    ++m.pattern_switches;
    last_pattern = a.pattern;
  }
  if (nearest && nearest_m < avoid_m && inSomeCone(ctx.robot.ultrasonic, st.pose, *nearest)) {
    m.visible_s += 0.01;
    if (!a.person) m.missed_s += 0.01;
  }
  if (nearest && nearest_m < avoid_m && a.person) {
    ++pattern_ticks;
    pattern_hits += a.pattern == tp ? 1 : 0;
    ++pattern_counts[static_cast<std::size_t>(a.pattern)];
  }
  if (opt.keep_series)
    run.series.push_back({t, st.pose.x_m, st.pose.y_m, st.pose.theta_rad, v, nearest_m,
                          a.person ? a.distance_m : -1.0, a.speed_factor, static_cast<int>(a.pattern),
                          static_cast<int>(tp)});

}

/// The run's last figures: duration, the automaton's switches, contacts,
/// pattern accuracy and the dominant pattern, false tracks, and why it failed.
void finishMetrics(ScenarioRun& run, const TruthTally& tally, const Simulation& sim, robot::RobotCore& core,
                   const behavior::HumanAwareness& awareness, const ScenarioSpec& spec) {
  RunMetrics& m = run.metrics;
  m.duration_s = sim.timeS();
  {
    v1::Telemetry tl;  // the navigation automaton's switches (kept after COMPLETED)
    core.fillTelemetry(tl, m.duration_s);
    m.mode_switches += tl.nav_switches();
  }
  m.person_collisions = sim.personCollisions();
  m.wall_collisions = sim.collisions();
  if (tally.pattern_ticks > 0) m.pattern_accuracy = static_cast<double>(tally.pattern_hits) / static_cast<double>(tally.pattern_ticks);
  uint64_t best = 0;
  for (std::size_t i = 1; i < tally.pattern_counts.size(); ++i)
    if (tally.pattern_counts[i] > best) {
      best = tally.pattern_counts[i];
      m.dominant_pattern = std::string(behavior::toString(static_cast<behavior::Pattern>(i)));
    }
  if (m.dominant_pattern.empty()) m.dominant_pattern = "none";
  m.false_tracks = awareness.tracker().counters().tracks_unconfirmed_dropped;
  if (m.failure.empty()) {
    if (!m.completed) m.failure = "not completed within " + std::to_string(static_cast<int>(spec.time_limit_s)) + " s";
    else if (m.person_collisions > 0) m.failure = std::to_string(m.person_collisions) + " collision(s) with people";
    else if (m.wall_collisions > 0) m.failure = std::to_string(m.wall_collisions) + " collision(s) with walls";
  }
  m.success = m.failure.empty();
}

}  // namespace

std::string ScenarioTask::describe() const {
  char buf[160];
  switch (kind) {
    case Kind::kLine: std::snprintf(buf, sizeof buf, "line %.1f m at %.2f m/s", length_m, speed_m_s); break;
    case Kind::kCircle:
      std::snprintf(buf, sizeof buf, "circle r %.1f m x %.2g at %.2f m/s", radius_m, laps, speed_m_s);
      break;
    case Kind::kGoTo:
      std::snprintf(buf, sizeof buf, "goto %zu point(s), last (%.1f, %.1f)", points_m.size(), points_m.back().first,
                    points_m.back().second);
      break;
  }
  return buf;
}

std::vector<ScenarioSpec> loadSuiteFile(const std::string& path) {
  const auto root = config::ConfigNode::loadFile(path);
  const auto slash = path.rfind('/');
  const std::string dir = slash == std::string::npos ? "." : path.substr(0, slash);
  std::vector<ScenarioSpec> out;
  for (const auto& n : root.children("scenarios")) {
    ScenarioSpec s;
    s.name = n.requireString("name");
    s.description = n.string("description", "");
    const std::string w = n.requireString("world");
    s.world_file = !w.empty() && w[0] == '/' ? w : dir + "/" + w;
    s.task = readTask(n.child("task"));
    s.expect_pattern = patternByName(n, "expect_pattern");
    s.time_limit_s = n.number("time_limit_s", s.time_limit_s, 1, 3600);
    const auto p = n.optChild("paper");
    s.paper.detect_s = optSeconds(p, "detect_s");
    s.paper.enter_avoidance_s = optSeconds(p, "enter_avoidance_s");
    s.paper.stop_s = optSeconds(p, "stop_s");
    s.paper.slowest_s = optSeconds(p, "slowest_s");
    for (const auto& o : out)
      if (o.name == s.name) n.fail("name", "scenario '" + s.name + "' appears twice");
    out.push_back(std::move(s));
  }
  root.checkKnown();
  if (out.empty()) throw config::ConfigError(path + ": scenarios: none given");
  for (auto& s : out) s.world = loadWorldFile(s.world_file);
  return out;
}

ScenarioContext loadScenarioContext(const std::string& robot_yaml, const std::string& control_yaml,
                                    const std::string& behavior_yaml) {
  ScenarioContext c;
  c.robot = config::loadRobotConfigFile(robot_yaml);
  c.control = config::loadControlConfigFile(control_yaml);
  config::applyRobot(c.control, c.robot);
  c.scheduler = config::loadScheduler(c.control);
  c.awareness = behavior::loadAwarenessConfigFile(behavior_yaml);
  (void)behavior::loadSpeedStrategy(c.awareness.speed_fis, c.awareness.speed);  // a bad rule base fails here, not mid-run
  return c;
}

ScenarioRun runScenario(const ScenarioSpec& spec, const ScenarioContext& ctx, const RunOptions& opt) {
  ScenarioRun run;
  run.scenario = spec.name;
  run.policy = opt.policy;
  run.people = opt.people;
  RunMetrics& m = run.metrics;

  World world = spec.world;
  if (!opt.people) world.pedestrians.clear();
  Simulation sim(ctx.robot, world, opt.seed);
  sim.setPeopleWaitForMotion(true);  // as mcu_sim --people-wait-motion in the full-stack test

  robot::RobotCore core(ctx.robot, robot::SafetyParams{}, ctx.control, ctx.scheduler);
  std::vector<robot::CoreEvent> events;  // the per-tick take's buffer, swapped with the core's
  behavior::AwarenessConfig acfg = ctx.awareness;
  acfg.enabled = true;
  acfg.policy = opt.policy;
  auto awareness = robot::makeAwareness(ctx.robot, acfg,
                                       opt.site_map ? world::mapFromWorld(world) : std::vector<geometry::Segment>{},
                                       "scenario behaviour config");
  behavior::HumanAwareness* aw = awareness.get();
  core.setAwareness(std::move(awareness));
  core.onSerialState(true, 0.0);
  core.onLinkUp(0.0);

  serial::FrameEncoder encoder;
  serial::FrameDecoder decoder;
  std::vector<uint8_t> rx;
  auto send = [&](const serial::Message& msg) {
    const auto f = encoder.encode(msg);
    sim.receive(f.span());
  };

  const v1::Command cmd = taskCommand(spec);

  const double avoid_m = acfg.speed.max_avoidance_m;
  TruthTally tally(acfg, sim.state().pose);
  bool sent = false;
  double cmd_time = -1;
  const uint64_t limit_ms = static_cast<uint64_t>(spec.time_limit_s * 1000.0);

  for (uint64_t t_ms = Simulation::kFramePeriod_ms; t_ms <= limit_ms; t_ms += Simulation::kFramePeriod_ms) {
    sim.advanceTo(t_ms);
    const double t = sim.timeS();
    if (opt.observer) opt.observer->beforeFrame(sim, *aw, t);
    sim.takeTx(rx);
    decoder.feed({rx.data(), rx.size()}, [&](const serial::Message& msg, uint8_t) {
      if (const auto* f = std::get_if<serial::SensorFrame>(&msg)) send(core.onSensorFrame(*f, t));
    });
    if (t_ms % 100 == 0) {  // the server's and the robot's heartbeats
      core.onLinkActivity(t);
      send(serial::Heartbeat{static_cast<uint32_t>(t_ms)});
    }
    if (auto c = core.onTimer(t)) send(*c);
    if (!sent && t >= kCommandTime_s) {
      const v1::Ack ack = core.onCommand(cmd, t);
      send(core.commandNow());
      sent = true;
      cmd_time = t;
      if (ack.status() != v1::Ack::ACCEPTED) {
        m.failure = "command rejected: " + ack.reason();
        break;
      }
    }
    core.takeEvents(events);
    for (const auto& e : events)
      if (e.kind == v1::Event::MODE_CHANGE && sent) ++m.mode_switches;
    for (const auto& a : core.takeAcks())
      if (a.command_id() == 1 && a.status() == v1::Ack::COMPLETED) {
        m.completed = true;
        m.time_to_goal_s = t - cmd_time;
      }

    tally.tick(run, sim, *aw, ctx, opt, avoid_m, t);
    if (opt.observer) opt.observer->afterTick(sim, *aw, t);
    if (m.completed) break;
    if (core.mode() == v1::FAILSAFE || core.mode() == v1::ESTOP) {
      m.failure = "robot latched " + std::string(v1::Mode_Name(core.mode()));
      break;
    }
  }
  finishMetrics(run, tally, sim, core, *aw, spec);
  return run;
}

}  // namespace inspect::sim
