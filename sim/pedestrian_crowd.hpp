#pragma once
// The world's scripted pedestrians in sim time: each appears at its route's
// first point at start_s, walks waypoint to waypoint (pausing where told) and
// is moved by the social force model (shared/behavior/social_force.hpp) among
// the other people, the walls and the robot. Deterministic: no randomness.
#include <cstddef>
#include <span>
#include <vector>

#include "shared/behavior/social_force.hpp"
#include "shared/geometry/circle.hpp"
#include "sim/sim_observer.hpp"
#include "sim/world_names.hpp"

namespace inspect::sim {

/// All pedestrians of a world; holds a reference to the world.
class PedestrianCrowd {
 public:
  /// Pedestrians with start_s = 0 appear at once; observer (may be null) hears
  /// of them at the first reportInitial() or step().
  PedestrianCrowd(const World& world, SimObserver* observer = nullptr);

  /// Reports (once) the pedestrians present from t = 0 as pedestrian_start
  /// events; separate from the constructor so that they follow the run's
  /// start event in the truth log.
  void reportInitial();

  /// Advances from t_s to t_s + dt_s against the robot's body at t_s, then
  /// lets appear whoever starts by t_s + dt_s. No allocation.
  void step(double t_s, double dt_s, const behavior::Agent& robot);

  /// Number of scripted pedestrians (present or not).
  std::size_t size() const { return progress_.size(); }
  /// True once pedestrian i has appeared (it never leaves again).
  bool present(std::size_t i) const { return progress_[i].present; }
  /// True once pedestrian i has reached the end of a non-looping route.
  bool finished(std::size_t i) const { return progress_[i].finished; }
  /// Body and motion of pedestrian i; meaningful only while present(i).
  const behavior::Agent& agent(std::size_t i) const { return agents_[progress_[i].slot]; }
  const PedestrianScript& script(std::size_t i) const { return world_.pedestrians[i]; }
  /// How far pedestrian i has walked and where they face (world frame): the
  /// camera draws their gait and their front, side or back from these.
  double walkedM(std::size_t i) const { return gait_[progress_[i].slot].walked_m; }
  double facingRad(std::size_t i) const { return gait_[progress_[i].slot].facing_rad; }
  /// Bodies of the present pedestrians, for the ultrasonic sensors.
  std::span<const Circle> circles() const { return circles_; }

 private:
  struct Progress {
    bool present = false;
    bool finished = false;
    bool pause_served = false;  // the pause at `target` has been taken
    std::size_t target = 0;     // index of the waypoint walked to
    double pause_left_s = 0.0;
    std::size_t slot = 0;       // index into agents_ once present
  };
  void appear(double t_s);
  void reportStart(std::size_t i, double t_s) const;
  void followRoute(std::size_t i, double t_s, double dt_s);
  double pauseAt(std::size_t i, std::size_t waypoint) const;

  const World& world_;
  SimObserver* observer_;
  bool started_ = false;  // step() has run at least once
  std::vector<behavior::WallSegment> walls_;
  std::vector<Progress> progress_;
  std::vector<behavior::Agent> agents_;  // present pedestrians only, in order of appearance
  std::vector<std::size_t> owner_;       // script index of each agents_ slot
  std::vector<Eigen::Vector2d> scratch_;
  std::vector<Circle> circles_;          // parallel to agents_
  struct Gait {
    double walked_m = 0.0;
    double facing_rad = 0.0;
  };
  std::vector<Gait> gait_;               // parallel to agents_
};

}  // namespace inspect::sim
