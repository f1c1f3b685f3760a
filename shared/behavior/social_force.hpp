#pragma once
// Social force model of walking people (paper Eqs 7-8; Helbing & Molnar 1995
// form): a driving term toward the goal plus exponential repulsions from other
// people, walls and the robot. Pure functions on plain structs: the simulator
// moves its pedestrians with them and the robot PREDICTS people with them.
// Forces are per unit mass (m/s^2). Parameters and their sources:
// docs/world-format.md ("social_force").
#include <cstddef>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "shared/config/config_node.hpp"
#include "shared/geometry/segment.hpp"

namespace inspect::behavior {

/// One exponential repulsion term: strength * exp((r_ij - d_ij) / range) * w(phi),
/// with the anisotropy w(phi) = anisotropy + (1 - anisotropy) (1 + cos phi) / 2
/// (phi: angle between the walking direction and the direction to the source;
/// anisotropy 1 = isotropic, 0 = blind to what is behind).
struct Repulsion {
  double strength_m_s2 = 0.0;  // A: acceleration at contact (d_ij = r_ij)
  double range_m = 0.1;        // B: e-folding length of the gap d_ij - r_ij
  double anisotropy = 1.0;     // lambda in [0, 1]
};

/// Model parameters. Defaults, sources and measured effect: the comments here
/// and docs/world-format.md ("social_force").
struct SocialForceParams {
  // Relaxation time of the driving term (v0 e - v) / tau (Helbing & Molnar 1995;
  // Helbing, Farkas & Vicsek 2000 use 0.5 s).
  double relaxation_time_s = 0.5;
  // Speed cap as a multiple of the desired speed v0 (Helbing & Molnar 1995: 1.3).
  double max_speed_factor = 1.3;
  // Social (long-range) repulsion between people, circular specification
  // (Helbing, Farkas & Vicsek 2000 form). Strength and range are ours, between
  // Helbing & Molnar 1995 (V0 = 2.1 m^2/s^2, sigma = 0.3 m: ~1.3 m/s^2 at the
  // contact of two 0.25 m people) and Helbing et al. 2005 (A = 3 m/s^2,
  // B = 0.2 m), with a longer range so that two people meeting head-on at
  // 0.5 m/s pass with ~0.37 m between their bodies, ~0.48 m when 0.3 m
  // offset (tests/sim/pedestrians). The form ignores speed: at 1.3 m/s the gaps
  // shrink to ~0.05-0.1 m. Anisotropy
  // 0.35: between Helbing et al. 2005 (0.75) and Johansson, Helbing & Shukla
  // 2007 (fits of 0.06-0.12).
  Repulsion people{2.0, 0.50, 0.35};
  // Walls and obstacle edges (nearest point of each edge), isotropic like
  // Helbing & Molnar 1995's wall potential, with Helbing et al. 2005's
  // A = 5 m/s^2, B = 0.1 m and no separate contact term: people pass a box
  // ~0.25 m off at 0.5 m/s and still get through a 0.8 m doorway.
  Repulsion walls{5.0, 0.10, 1.0};
  // The robot: people give a machine more room than a person (the paper's
  // "sensitive area"); same form, stronger and longer than between people: a
  // standing robot is passed with ~0.49 m between the bodies.
  Repulsion robot{3.0, 0.60, 0.35};
  // Body contact, isotropic, between people and between a person and the
  // robot, on top of the terms above: Helbing, Farkas & Vicsek 2000,
  // A = 2000 N / 80 kg, B = 0.08 m.
  Repulsion contact{25.0, 0.08, 1.0};
  // Sidestep (our addition): this fraction of the social push from a person
  // or the robot AHEAD (scaled by cos phi >= 0) is added sideways, away from
  // the side their centre is on, and to the right when it lies within 5 cm of
  // the walking line. Without it two people (or a person and the robot)
  // exactly head-on push straight back and stop face to face; with it they
  // pass, keeping right when nothing else decides (a side preference of the
  // kind Helbing & Molnar 1995 discuss as an asymmetry of the interaction).
  // Both see each other on the same side, so they always agree. 0.5 turns
  // the push from someone dead ahead ~27 degrees aside: people meeting
  // head-on at 0.5 m/s lose ~1.5 s instead of ~3 s with 0.1.
  double sidestep = 0.5;
};

/// A walking person (or the robot, as a source of repulsion). Positions in the
/// world frame.
struct Agent {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d velocity_m_s = Eigen::Vector2d::Zero();
  Eigen::Vector2d goal_direction = Eigen::Vector2d::Zero();  // unit vector e, or zero = stand still
  double desired_speed_m_s = 0.5;                            // v0
  double radius_m = 0.25;
  // False: someone distracted or carrying something, who keeps their line:
  // the robot's social repulsion and sidestep are not felt, only body
  // contact stops them (people and walls are still felt).
  bool notices_robot = true;
};

/// A wall or obstacle edge that repels people (two-sided). Where another
/// segment ends at the same point (a polyline or polygon corner), set the
/// joined flag: both edges' nearest point is then that corner, and each
/// pushes with half strength so the corner is not counted twice.
struct WallSegment {
  geometry::Segment edge;  // metres
  bool a_joined = false;
  bool b_joined = false;
};
/// The walls an agent sees (polygons given as their edges).
using WallView = std::span<const WallSegment>;

/// The terms of Eq 7 for one agent, m/s^2 (force per unit mass).
struct SocialForce {
  Eigen::Vector2d driving_m_s2 = Eigen::Vector2d::Zero();  // F_acc: (v0 e - v) / tau
  Eigen::Vector2d people_m_s2 = Eigen::Vector2d::Zero();   // F_int from other people
  Eigen::Vector2d walls_m_s2 = Eigen::Vector2d::Zero();    // F_int from walls and obstacles
  Eigen::Vector2d robot_m_s2 = Eigen::Vector2d::Zero();    // F_int from the robot
  /// Eq 7: the sum of all terms.
  Eigen::Vector2d total() const { return driving_m_s2 + people_m_s2 + walls_m_s2 + robot_m_s2; }
};

/// w(phi) for a source in direction to_source from an agent walking along
/// heading (both need not be unit length); 1 when either is zero.
double anisotropyWeight(double anisotropy, const Eigen::Vector2d& heading, const Eigen::Vector2d& to_source);

/// Acceleration of `self` (Eq 7). `others` may contain `self` (skipped by
/// address); `robot` may be null. Non-finite input gives a zero force.
SocialForce computeForce(const Agent& self, std::span<const Agent> others, WallView walls, const Agent* robot,
                         const SocialForceParams& p);

/// One semi-implicit Euler step (Eq 8, dv/dt = F / m): v += a dt, |v| capped at
/// max_speed_factor * v0, x += v dt. Non-finite acceleration counts as zero.
void integrate(Agent& agent, const Eigen::Vector2d& accel_m_s2, const SocialForceParams& p, double dt_s);

/// Advances all agents by dt_s at once (every force from the same instant).
/// scratch must hold at least agents.size() entries; nothing is allocated.
void stepAgents(std::span<Agent> agents, WallView walls, const Agent* robot, const SocialForceParams& p, double dt_s,
                std::span<Eigen::Vector2d> scratch);

/// Predicts a person's positions at dt_s, 2 dt_s, ... into out (its size sets
/// the horizon) and returns how many were written (0 for a bad dt_s). The
/// person keeps walking in the direction of their current velocity at their
/// current speed (a person slower than 0.05 m/s is assumed to stand) and is
/// repelled by the walls and by the robot, which keeps its current velocity.
/// Integrated in sub-steps of at most 20 ms; nothing is allocated.
std::size_t predictPath(const Agent& person, const Agent* robot, WallView walls, const SocialForceParams& p,
                        double dt_s, std::span<Eigen::Vector2d> out);
/// Same, for horizon_s (rounded down to whole dt_s steps).
std::vector<Eigen::Vector2d> predictPath(const Agent& person, const Agent* robot, WallView walls,
                                         const SocialForceParams& p, double horizon_s, double dt_s);

/// Eq 8, second line: the avoidance distance the robot must still keep,
/// R_theta,avoid = R_r,avoid - v t, i.e. the human avoidance distance less the
/// distance the robot covers in t; clamped to [0, R_r,avoid]. A negative or
/// NaN v t counts as 0 (the full distance); a negative or non-finite
/// R_r,avoid gives 0.
double avoidanceDistance(double human_avoid_m, double robot_speed_m_s, double t_s);

/// Reads a `social_force` mapping (every key optional, defaults above); throws
/// config::ConfigError naming file, key and reason.
SocialForceParams readSocialForceParams(const config::ConfigNode& n);

}  // namespace inspect::behavior
