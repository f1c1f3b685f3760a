#include "shared/behavior/social_force.hpp"

#include <algorithm>
#include <cmath>
#include <functional>

namespace inspect::behavior {
namespace {

constexpr double kTiny = 1e-9;
// exp() of a deep overlap would overflow; e^10 x 25 m/s^2 already stops anyone within a step.
constexpr double kMaxExponent = 10.0;
// Sub-step of predictPath: the contact term (25 m/s^2 over 0.08 m) needs ~20 ms or less.
constexpr double kMaxPredictStep_s = 0.02;
// A source within this distance of the walking line counts as dead ahead: sidestep to the right.
constexpr double kSidestepTie_m = 0.05;
// Walls have no separate contact term: their own term is already short-ranged.
constexpr Repulsion kNoContact{0.0, 1.0, 1.0};
// Slower than this, a person is predicted to stand.
constexpr double kStandingSpeed_m_s = 0.05;

bool finite(const Eigen::Vector2d& v) { return std::isfinite(v.x()) && std::isfinite(v.y()); }

// Counter-clockwise perpendicular.
Eigen::Vector2d perp(const Eigen::Vector2d& v) { return {-v.y(), v.x()}; }

Eigen::Vector2d unitOr(const Eigen::Vector2d& v, const Eigen::Vector2d& fallback) {
  const double n = v.norm();
  return n > kTiny ? Eigen::Vector2d(v / n) : fallback;
}

// The walking direction that decides what is "ahead": the desired direction
// (Helbing & Molnar 1995), else the velocity of someone pushed while standing.
Eigen::Vector2d headingOf(const Agent& a) {
  return a.goal_direction.squaredNorm() > kTiny ? a.goal_direction : a.velocity_m_s;
}

double magnitude(const Repulsion& r, double gap_m) {
  if (!(r.strength_m_s2 > 0.0) || !(r.range_m > 0.0)) return 0.0;
  return r.strength_m_s2 * std::exp(std::min(-gap_m / r.range_m, kMaxExponent));
}

// Social + contact push along the unit vector n (pointing from the source to
// the agent), for a gap between the bodies of gap_m, plus the sidestep.
Eigen::Vector2d push(const Eigen::Vector2d& n, double gap_m, const Repulsion& social, const Repulsion& contact,
                     const Eigen::Vector2d& heading, double sidestep, double lateral_m) {
  const Eigen::Vector2d to_source = -n;
  const double social_m = magnitude(social, gap_m) * anisotropyWeight(social.anisotropy, heading, to_source);
  const double contact_m = magnitude(contact, gap_m) * anisotropyWeight(contact.anisotropy, heading, to_source);
  Eigen::Vector2d f = (social_m + contact_m) * n;
  const double hn = heading.norm();
  if (sidestep > 0.0 && hn > kTiny) {
    const Eigen::Vector2d h = heading / hn;
    const double ahead = std::max(0.0, h.dot(to_source));  // cos phi, 0 for sources beside or behind
    const Eigen::Vector2d right(h.y(), -h.x());
    // lateral_m: the source's offset to the LEFT of the walking line.
    const double side = lateral_m >= -kSidestepTie_m ? 1.0 : -1.0;
    f += sidestep * social_m * ahead * side * right;
  }
  return f;
}

// Offset of point q to the left of the line through p along heading.
double leftOffset(const Eigen::Vector2d& p, const Eigen::Vector2d& heading, const Eigen::Vector2d& q) {
  const double hn = heading.norm();
  if (hn <= kTiny) return 0.0;
  const Eigen::Vector2d d = q - p;
  return (heading.x() * d.y() - heading.y() * d.x()) / hn;
}

// Position of the point of s nearest to p, as a fraction u in [0, 1] from a to b.
double nearestFraction(const WallSegment& s, const Eigen::Vector2d& p) {
  const geometry::Vec2 e = s.edge.b - s.edge.a;
  const double len2 = dot(e, e);
  return len2 > 0.0 ? std::clamp(dot(geometry::Vec2{p.x(), p.y()} - s.edge.a, e) / len2, 0.0, 1.0) : 0.0;
}

Eigen::Vector2d eigen(geometry::Vec2 v) { return {v.x, v.y}; }

}  // namespace

double anisotropyWeight(double anisotropy, const Eigen::Vector2d& heading, const Eigen::Vector2d& to_source) {
  const double hn = heading.norm();
  const double tn = to_source.norm();
  if (hn <= kTiny || tn <= kTiny) return 1.0;
  const double cos_phi = std::clamp(heading.dot(to_source) / (hn * tn), -1.0, 1.0);
  return anisotropy + (1.0 - anisotropy) * (1.0 + cos_phi) / 2.0;
}

SocialForce computeForce(const Agent& self, std::span<const Agent> others, WallView walls, const Agent* robot,
                         const SocialForceParams& p) {
  SocialForce f;
  if (!finite(self.position_m) || !finite(self.velocity_m_s) || !finite(self.goal_direction) ||
      !std::isfinite(self.desired_speed_m_s) || !std::isfinite(self.radius_m))
    return f;
  const Eigen::Vector2d heading = headingOf(self);
  // Coincident bodies have no direction between them; any fixed choice must
  // still push two of them apart, hence the sign from their (array) order.
  const Eigen::Vector2d side = unitOr(perp(heading), Eigen::Vector2d::UnitX());

  const double tau = std::max(p.relaxation_time_s, 1e-3);
  f.driving_m_s2 = (self.desired_speed_m_s * self.goal_direction - self.velocity_m_s) / tau;

  for (const Agent& o : others) {
    if (&o == &self || !finite(o.position_m)) continue;
    const Eigen::Vector2d diff = self.position_m - o.position_m;
    const double d = diff.norm();
    Eigen::Vector2d n;
    if (d > kTiny) {
      n = diff / d;
    } else {
      const double sign = std::less<const Agent*>{}(&self, &o) ? 1.0 : -1.0;
      n = unitOr(self.velocity_m_s - o.velocity_m_s, sign * side);
    }
    f.people_m_s2 += push(n, d - (self.radius_m + o.radius_m), p.people, p.contact, heading, p.sidestep,
                          leftOffset(self.position_m, heading, o.position_m));
  }

  for (const WallSegment& s : walls) {
    const double u = nearestFraction(s, self.position_m);
    const Eigen::Vector2d a = eigen(s.edge.a), b = eigen(s.edge.b);
    const Eigen::Vector2d diff = self.position_m - (a + u * (b - a));
    const double d = diff.norm();
    const Eigen::Vector2d n = d > kTiny ? Eigen::Vector2d(diff / d) : unitOr(perp(b - a), side);
    const bool shared_corner = (u <= 0.0 && s.a_joined) || (u >= 1.0 && s.b_joined);
    f.walls_m_s2 += (shared_corner ? 0.5 : 1.0) * push(n, d - self.radius_m, p.walls, kNoContact, heading, 0.0, 0.0);
  }

  if (robot && finite(robot->position_m)) {
    const Eigen::Vector2d diff = self.position_m - robot->position_m;
    const double d = diff.norm();
    const Eigen::Vector2d n = d > kTiny ? Eigen::Vector2d(diff / d) : side;
    constexpr Repulsion kUnnoticed{0.0, 1.0, 1.0};
    f.robot_m_s2 = push(n, d - (self.radius_m + robot->radius_m), self.notices_robot ? p.robot : kUnnoticed,
                        p.contact, heading, self.notices_robot ? p.sidestep : 0.0,
                        leftOffset(self.position_m, heading, robot->position_m));
  }

  for (Eigen::Vector2d* t : {&f.driving_m_s2, &f.people_m_s2, &f.walls_m_s2, &f.robot_m_s2})
    if (!finite(*t)) t->setZero();
  return f;
}

void integrate(Agent& agent, const Eigen::Vector2d& accel_m_s2, const SocialForceParams& p, double dt_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) return;
  if (finite(accel_m_s2)) agent.velocity_m_s += accel_m_s2 * dt_s;
  if (!finite(agent.velocity_m_s)) agent.velocity_m_s.setZero();
  const double v_max = std::max(0.0, p.max_speed_factor * agent.desired_speed_m_s);
  const double speed = agent.velocity_m_s.norm();
  if (speed > v_max) agent.velocity_m_s *= speed > 0.0 ? v_max / speed : 0.0;
  agent.position_m += agent.velocity_m_s * dt_s;
}

void stepAgents(std::span<Agent> agents, WallView walls, const Agent* robot, const SocialForceParams& p, double dt_s,
                std::span<Eigen::Vector2d> scratch) {
  if (scratch.size() < agents.size()) return;
  const std::span<const Agent> all(agents.data(), agents.size());
  for (std::size_t i = 0; i < agents.size(); ++i) scratch[i] = computeForce(agents[i], all, walls, robot, p).total();
  for (std::size_t i = 0; i < agents.size(); ++i) integrate(agents[i], scratch[i], p, dt_s);
}

std::size_t predictPath(const Agent& person, const Agent* robot, WallView walls, const SocialForceParams& p,
                        double dt_s, std::span<Eigen::Vector2d> out) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s) || !finite(person.position_m) || !finite(person.velocity_m_s)) return 0;
  Agent a = person;
  const double speed = a.velocity_m_s.norm();
  if (speed < kStandingSpeed_m_s) {
    a.velocity_m_s.setZero();
    a.goal_direction.setZero();
    a.desired_speed_m_s = 0.0;
  } else {
    a.goal_direction = a.velocity_m_s / speed;
    a.desired_speed_m_s = speed;
  }
  Agent r;
  if (robot) r = *robot;
  const int sub = std::max(1, static_cast<int>(std::ceil(dt_s / kMaxPredictStep_s)));
  const double h = dt_s / sub;
  for (std::size_t k = 0; k < out.size(); ++k) {
    for (int i = 0; i < sub; ++i) {
      const SocialForce f = computeForce(a, {}, walls, robot ? &r : nullptr, p);
      integrate(a, f.total(), p, h);
      if (robot && finite(r.velocity_m_s)) r.position_m += r.velocity_m_s * h;
    }
    out[k] = a.position_m;
  }
  return out.size();
}

std::vector<Eigen::Vector2d> predictPath(const Agent& person, const Agent* robot, WallView walls,
                                         const SocialForceParams& p, double horizon_s, double dt_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s) || !(horizon_s > 0.0) || !std::isfinite(horizon_s)) return {};
  // The small epsilon keeps horizon 2.0 / dt 0.1 at 20 steps despite rounding.
  const auto steps = static_cast<std::size_t>(std::floor(horizon_s / dt_s + 1e-9));
  std::vector<Eigen::Vector2d> out(steps);
  out.resize(predictPath(person, robot, walls, p, dt_s, out));
  return out;
}

double avoidanceDistance(double human_avoid_m, double robot_speed_m_s, double t_s) {
  if (!std::isfinite(human_avoid_m) || human_avoid_m <= 0.0) return 0.0;
  double covered_m = robot_speed_m_s * t_s;
  if (std::isnan(covered_m) || covered_m < 0.0) covered_m = 0.0;
  return std::max(0.0, human_avoid_m - covered_m);  // Eq 8
}

SocialForceParams readSocialForceParams(const config::ConfigNode& n) {
  SocialForceParams p;
  p.relaxation_time_s = n.number("relaxation_time_s", p.relaxation_time_s, 0.05, 10.0);
  p.max_speed_factor = n.number("max_speed_factor", p.max_speed_factor, 1.0, 3.0);
  const auto read = [&](const char* key, Repulsion& r) {
    const auto c = n.optChild(key);
    r.strength_m_s2 = c.number("strength_m_s2", r.strength_m_s2, 0.0, 1000.0);
    r.range_m = c.number("range_m", r.range_m, 0.01, 5.0);
    r.anisotropy = c.number("anisotropy", r.anisotropy, 0.0, 1.0);
  };
  read("people", p.people);
  read("walls", p.walls);
  read("robot", p.robot);
  read("contact", p.contact);
  p.sidestep = n.number("sidestep", p.sidestep, 0.0, 1.0);
  return p;
}

}  // namespace inspect::behavior
