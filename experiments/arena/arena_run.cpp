#include "experiments/arena/arena_run.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

#include "shared/world/world.hpp"
#include "sim/simulation.hpp"

namespace inspect::arena {
namespace {

constexpr double kTick_s = 0.01;
constexpr double kIntimateGap_m = 0.45;  // Hall: intimate distance, body to body
constexpr double kPersonalGap_m = 1.2;   // Hall: end of the personal distance
constexpr double kFaultSpeed_m_s = 0.02; // the robot approaching faster than this at contact is at fault
// Bodies within this count as touching: the model's contact term (25 m/s^2 over
// 0.08 m) already pushes at 13 m/s^2 here, so a soft-body model rarely reaches 0.
constexpr double kContactGap_m = 0.05;
constexpr double kFalseTrack_m = 1.0;    // a new person track this far from every true person is false

TruePerson truthOf(const behavior::Agent& a) {
  return {{a.position_m.x(), a.position_m.y()}, {a.velocity_m_s.x(), a.velocity_m_s.y()}, a.radius_m};
}

class ArenaObserver final : public sim::RunObserver {
 public:
  ArenaObserver(const Episode& e, const sim::ScenarioContext& ctx, bool oracle, const ArenaCamera& camera)
      : world_(e.spec.world), ctx_(ctx), oracle_(oracle), avoid_m_(ctx.awareness.speed.max_avoidance_m),
        camera_(world_, ctx.robot, ctx.awareness, camera, e.seed) {}

  void beforeFrame(const sim::Simulation& sim, behavior::HumanAwareness& aw, double t_s) override {
    camera_.beforeFrame(sim, aw, t_s);
    if (!oracle_) return;
    // The true nearest person the robot should react to: in line of sight and
    // sonar range, with a pattern (else the nearest, who needs no reaction).
    const auto& pose = sim.state().pose;
    const auto& crowd = sim.pedestrians();
    behavior::SpeedInput best, any;
    for (std::size_t i = 0; i < crowd.size(); ++i) {
      if (!crowd.present(i)) continue;
      const TruePerson p = truthOf(crowd.agent(i));
      const double dx = p.position.x - pose.x_m, dy = p.position.y - pose.y_m, d = std::hypot(dx, dy);
      if (d > ctx_.robot.ultrasonic.max_range_m + p.radius_m) continue;
      const auto hit = world::castRay(world_, {pose.x_m, pose.y_m}, std::atan2(dy, dx), d);
      if (hit && *hit < d - p.radius_m) continue;
      const behavior::SpeedInput in{true, d, std::hypot(p.velocity.x, p.velocity.y), truePattern(pose, p)};
      if (!any.person || d < any.distance_m) any = in;
      if (in.pattern != behavior::Pattern::kNone && (!best.person || d < best.distance_m)) best = in;
    }
    aw.overrideNextSpeedInput(best.person ? best : any);
  }

  void afterTick(const sim::Simulation& sim, const behavior::HumanAwareness& aw, double t_s) override {
    const auto& pose = sim.state().pose;
    const behavior::Agent robot = sim.robotBody();
    const auto& crowd = sim.pedestrians();
    if (have_last_) {
      const double step = std::hypot(pose.x_m - last_.x_m, pose.y_m - last_.y_m);
      path_m_ += step;
      turned_rad_ += std::abs(control::wrapAngle(pose.theta_rad - last_.theta_rad));
    } else {
      first_theta_ = pose.theta_rad;
    }
    last_ = pose;
    have_last_ = true;

    double tick_min_gap = 1e9;
    bool any_present = false, robot_closing_in_intimate = false;
    int observed = -1;
    double observed_d = 0;
    if (in_contact_.size() < crowd.size()) in_contact_.resize(crowd.size(), false);
    for (std::size_t i = 0; i < crowd.size(); ++i) {
      if (!crowd.present(i)) continue;
      const TruePerson p = truthOf(crowd.agent(i));
      const double dx = p.position.x - pose.x_m, dy = p.position.y - pose.y_m, d = std::hypot(dx, dy);
      const double gap = d - robot.radius_m - p.radius_m;
      tick_min_gap = std::min(tick_min_gap, gap);
      any_present = true;
      const bool contact = gap < kContactGap_m;
      if (contact && !in_contact_[i]) {
        // Fault: was the robot moving towards the person at contact?
        const double closing = d > 1e-9 ? (robot.velocity_m_s.x() * dx + robot.velocity_m_s.y() * dy) / d : 0.0;
        (closing > kFaultSpeed_m_s ? m.robot_fault : m.person_fault) += 1;
      }
      in_contact_[i] = contact;
      if (gap < kIntimateGap_m && d > 1e-9 &&
          (robot.velocity_m_s.x() * dx + robot.velocity_m_s.y() * dy) / d > kFaultSpeed_m_s)
        robot_closing_in_intimate = true;
      if (d < avoid_m_ && (observed < 0 || d < observed_d) && observable(pose, p, ctx_.robot.ultrasonic, world_)) {
        observed = static_cast<int>(i);
        observed_d = d;
      }
    }
    if (any_present) {
      const double g = std::max(0.0, tick_min_gap);  // 0 = contact
      m.min_gap_m = m.min_gap_m < 0 ? g : std::min(m.min_gap_m, g);
      if (tick_min_gap < kIntimateGap_m) m.intimate_s += kTick_s;
      if (robot_closing_in_intimate) m.intimate_robot_s += kTick_s;
      if (tick_min_gap < kPersonalGap_m) m.personal_s += kTick_s;
    }
    const auto& a = aw.last();
    if (observed >= 0) {
      const int truth = static_cast<int>(truePattern(pose, truthOf(crowd.agent(static_cast<std::size_t>(observed)))));
      const int reported = a.person ? static_cast<int>(a.pattern) : kUnseen;
      ++m.confusion[static_cast<std::size_t>(truth)][static_cast<std::size_t>(reported)];
    }
    // False people: a track that became a person where nobody is. The
    // odometry frame is the world frame here (every episode starts at the
    // origin facing +x) up to the odometry's drift.
    for (const auto& tr : aw.tracker().tracks()) {
      if (!tr.isPerson() || judged_.count(tr.id)) continue;
      double nearest = 1e9;
      for (std::size_t i = 0; i < crowd.size(); ++i)
        if (crowd.present(i))
          nearest = std::min(nearest, std::hypot(crowd.agent(i).position_m.x() - tr.x[0],
                                                 crowd.agent(i).position_m.y() - tr.x[1]));
      judged_[tr.id] = nearest > kFalseTrack_m;
      if (nearest > kFalseTrack_m) {
        ++m.false_people;
        ++m.false_where[static_cast<std::size_t>(falseWhere(pose, tr))];
      }
    }
    (void)t_s;
  }

  FalseWhereKind falseWhere(const control::Pose2& pose, const behavior::HumanTrack& tr) const {
    const auto& mount = ctx_.robot.camera;
    const control::Pose2 lens = config::mountPose(pose, {mount.x_m, mount.y_m, 0.0});
    const double dx = tr.x[0] - lens.x_m, dy = tr.x[1] - lens.y_m;
    const double bearing = std::abs(control::wrapAngle(std::atan2(dy, dx) - pose.theta_rad));
    if (bearing <= mount.hfov_deg * M_PI / 360.0)
      return ctx_.awareness.tracker.camera.recallAt(std::hypot(dx, dy)) > 0 ? kFalseInViewReached : kFalseInViewNear;
    return bearing <= 2 * M_PI / 3 ? kFalseBeside : kFalseBehind;
  }

  void finish() {
    m.path_m = path_m_;
    m.looks = static_cast<uint32_t>(camera_.activeLook().looks);
    m.ptz_off_path_s = camera_.activeLook().off_path_s;
    const double needed = std::abs(control::wrapAngle(last_.theta_rad - first_theta_));
    m.irregularity_rad_m = path_m_ > 0.1 ? std::max(0.0, turned_rad_ - needed) / path_m_ : 0.0;
    std::array<uint64_t, kPatterns> truth{}, reported{};
    for (int r = 1; r < kPatterns; ++r) {
      for (int c = 0; c <= kPatterns; ++c) truth[static_cast<std::size_t>(r)] += m.confusion[r][c];
      for (int c = 1; c < kPatterns; ++c) reported[static_cast<std::size_t>(c)] += m.confusion[r][c];
    }
    auto argmax = [](const std::array<uint64_t, kPatterns>& v) {
      int best = -1;
      for (int k = 1; k < kPatterns; ++k)
        if (v[static_cast<std::size_t>(k)] > 0 && (best < 0 || v[static_cast<std::size_t>(k)] > v[static_cast<std::size_t>(best)]))
          best = k;
      return best;
    };
    m.true_dominant = argmax(truth);
    m.reported_dominant = argmax(reported);
  }

  EpisodeMetrics m;

 private:
  const world::World& world_;
  const sim::ScenarioContext& ctx_;
  bool oracle_;
  double avoid_m_;
  sim::CameraLooks camera_;
  std::vector<bool> in_contact_;
  std::map<int, bool> judged_;
  control::Pose2 last_;
  bool have_last_ = false;
  double first_theta_ = 0, path_m_ = 0, turned_rad_ = 0;
};

EpisodeMetrics finishRun(ArenaObserver& obs, const sim::ScenarioRun& run, double reference_s) {
  obs.finish();
  EpisodeMetrics m = obs.m;
  const auto& r = run.metrics;
  m.success = r.success;
  m.failure = r.failure;
  m.timeout = !r.completed && r.failure.rfind("not completed", 0) == 0;
  m.time_to_goal_s = r.completed ? r.time_to_goal_s : -1;
  m.time_lost_s = r.completed && reference_s > 0 ? r.time_to_goal_s - reference_s : -1;
  m.wall_collisions = static_cast<uint32_t>(r.wall_collisions);
  m.max_jerk_m_s3 = r.max_jerk_m_s3;
  m.duration_s = r.duration_s;
  return m;
}

}  // namespace

const char* falseWhereName(int k) {
  static constexpr std::array<const char*, kFalseWhereKinds> kNames{"in view, reached", "in view, near", "beside",
                                                                     "behind"};
  return k >= 0 && k < kFalseWhereKinds ? kNames[static_cast<std::size_t>(k)] : "?";
}

const char* toString(Policy p) {
  switch (p) {
    case Policy::kStrategy: return "strategy";
    case Policy::kPlain: return "plain_tracking";
    case Policy::kStopAndWait: return "stop_and_wait";
    case Policy::kNoPattern: return "no_pattern";
    case Policy::kOracle: return "oracle";
  }
  return "?";
}

behavior::SpeedPolicy speedPolicy(Policy p) {
  switch (p) {
    case Policy::kPlain: return behavior::SpeedPolicy::kNone;
    case Policy::kStopAndWait: return behavior::SpeedPolicy::kStopAndWait;
    case Policy::kNoPattern: return behavior::SpeedPolicy::kFuzzyNoPattern;
    case Policy::kStrategy:
    case Policy::kOracle: return behavior::SpeedPolicy::kFuzzy;
  }
  return behavior::SpeedPolicy::kFuzzy;
}

EpisodeMetrics runEpisode(const Episode& e, const sim::ScenarioContext& ctx, Policy p, double reference_s,
                          const ArenaCamera& camera, bool site_map, sim::ScenarioRun* series) {
  ArenaObserver obs(e, ctx, p == Policy::kOracle, camera);
  sim::RunOptions opt;
  opt.policy = speedPolicy(p);
  opt.people = true;
  opt.seed = static_cast<uint32_t>(e.seed);
  opt.keep_series = series != nullptr;
  opt.observer = &obs;
  opt.site_map = site_map;
  sim::ScenarioRun run = sim::runScenario(e.spec, ctx, opt);
  EpisodeMetrics m = finishRun(obs, run, reference_s);
  if (series) *series = std::move(run);
  return m;
}

EpisodeMetrics runReference(const Episode& e, const sim::ScenarioContext& ctx, const ArenaCamera& camera,
                            bool site_map) {
  ArenaObserver obs(e, ctx, false, camera);
  sim::RunOptions opt;
  opt.policy = behavior::SpeedPolicy::kNone;
  opt.people = false;
  opt.seed = static_cast<uint32_t>(e.seed);
  opt.observer = &obs;
  opt.site_map = site_map;
  const sim::ScenarioRun run = sim::runScenario(e.spec, ctx, opt);
  return finishRun(obs, run, -1);
}

}  // namespace inspect::arena
