#include "sim/pedestrian_crowd.hpp"

#include <cstdio>

namespace inspect::sim {
namespace {

// Sim times are whole milliseconds; this keeps start_s = 2.0 at t = 2.000 s.
constexpr double kTimeEps_s = 1e-9;

Eigen::Vector2d toEigen(Vec2 p) { return {p.x, p.y}; }

}  // namespace

PedestrianCrowd::PedestrianCrowd(const World& world, SimObserver* observer)
    : world_(world), observer_(observer), walls_(solidEdges(world)), progress_(world.pedestrians.size()) {
  const std::size_t n = world.pedestrians.size();
  agents_.reserve(n);
  owner_.reserve(n);
  scratch_.resize(n);
  circles_.reserve(n);
  gait_.reserve(n);
  appear(0.0);
}

void PedestrianCrowd::reportStart(std::size_t i, double t_s) const {
  if (!observer_) return;
  const auto& s = world_.pedestrians[i];
  char detail[160];
  std::snprintf(detail, sizeof detail, "id=%s x=%.3f y=%.3f", s.id.c_str(), s.route.front().x, s.route.front().y);
  observer_->onEvent(t_s, "pedestrian_start", detail);
}

double PedestrianCrowd::pauseAt(std::size_t i, std::size_t waypoint) const {
  for (const auto& p : world_.pedestrians[i].pauses)
    if (p.at == waypoint) return p.duration_s;
  return 0.0;
}

void PedestrianCrowd::appear(double t_s) {
  for (std::size_t i = 0; i < progress_.size(); ++i) {
    auto& pr = progress_[i];
    const auto& s = world_.pedestrians[i];
    if (pr.present || t_s + kTimeEps_s < s.start_s) continue;
    pr.present = true;
    pr.slot = agents_.size();
    behavior::Agent a;
    a.position_m = toEigen(s.route.front());
    a.desired_speed_m_s = s.speed_m_s;
    a.radius_m = s.radius_m;
    a.notices_robot = s.notices_robot;
    agents_.push_back(a);
    owner_.push_back(i);
    circles_.push_back({s.route.front(), s.radius_m});
    // Facing their route's second point until they walk.
    const Vec2 next = s.route.size() > 1 ? s.route[1] : s.route.front();
    gait_.push_back({0.0, s.route.size() > 1 ? std::atan2(next.y - s.route.front().y, next.x - s.route.front().x) : 0.0});
    if (started_) reportStart(i, t_s);
  }
}

void PedestrianCrowd::followRoute(std::size_t i, double t_s, double dt_s) {
  auto& pr = progress_[i];
  const auto& s = world_.pedestrians[i];
  behavior::Agent& a = agents_[pr.slot];
  // Bounded: a looping route whose points all lie within arrive_m must not spin.
  for (std::size_t guard = 0; guard <= s.route.size() && !pr.finished && pr.pause_left_s <= 0.0; ++guard) {
    if ((toEigen(s.route[pr.target]) - a.position_m).norm() > s.arrive_m) break;
    const double pause_s = pauseAt(i, pr.target);
    if (!pr.pause_served && pause_s > 0.0) {
      pr.pause_left_s = pause_s;
      pr.pause_served = true;
      break;
    }
    pr.pause_served = false;
    if (pr.target + 1 < s.route.size()) {
      ++pr.target;
    } else if (s.loop) {
      pr.target = 0;
    } else {
      pr.finished = true;
      if (observer_) {
        char detail[160];
        std::snprintf(detail, sizeof detail, "id=%s x=%.3f y=%.3f", s.id.c_str(), a.position_m.x(),
                      a.position_m.y());
        observer_->onEvent(t_s, "pedestrian_end", detail);
      }
    }
  }
  if (pr.finished || pr.pause_left_s > 0.0) {
    a.goal_direction.setZero();
    pr.pause_left_s -= dt_s;
    return;
  }
  const Eigen::Vector2d to_goal = toEigen(s.route[pr.target]) - a.position_m;
  const double d = to_goal.norm();
  a.goal_direction = d > 1e-9 ? Eigen::Vector2d(to_goal / d) : Eigen::Vector2d::Zero();
}

void PedestrianCrowd::reportInitial() {
  if (started_) return;
  started_ = true;
  for (std::size_t i = 0; i < progress_.size(); ++i)
    if (progress_[i].present) reportStart(i, 0.0);
}

void PedestrianCrowd::step(double t_s, double dt_s, const behavior::Agent& robot) {
  reportInitial();
  for (std::size_t k = 0; k < agents_.size(); ++k) followRoute(owner_[k], t_s, dt_s);
  behavior::stepAgents(agents_, walls_, &robot, world_.social_force, dt_s, scratch_);
  for (std::size_t k = 0; k < agents_.size(); ++k) {
    const Eigen::Vector2d moved = Eigen::Vector2d(agents_[k].position_m.x(), agents_[k].position_m.y()) -
                                  Eigen::Vector2d(circles_[k].centre.x, circles_[k].centre.y);
    const double v = agents_[k].velocity_m_s.norm();
    gait_[k].walked_m += moved.norm();
    // Someone turns to where they walk; standing (or pushed slowly), they keep their facing.
    if (v > 0.15) gait_[k].facing_rad = std::atan2(agents_[k].velocity_m_s.y(), agents_[k].velocity_m_s.x());
    circles_[k].centre = {agents_[k].position_m.x(), agents_[k].position_m.y()};
  }
  appear(t_s + dt_s);
}

}  // namespace inspect::sim
