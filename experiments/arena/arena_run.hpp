#pragma once
// One arena episode with one policy (docs/scenarios.md, "The arena"): the
// scenario runner's in-process stack (the robot's decision core over the
// serial codec, the simulator) watched tick by tick against the ground truth
// (ground_truth.hpp): collisions split by fault, proxemic zone times, the
// confusion of reported vs true pattern on observable ticks, false people.
#include <array>
#include <cstdint>
#include <string>

#include "experiments/arena/episode.hpp"
#include "experiments/arena/ground_truth.hpp"
#include "experiments/scenarios/scenario_camera.hpp"

namespace inspect::arena {

/// The policies compared (what perception costs apart from what the rule base costs).
enum class Policy {
  kStrategy,    // the robot as shipped: tracker, classifier, Eq 9
  kPlain,       // plain tracking: people never change the speed
  kStopAndWait, // stop while anyone is within the max avoidance distance
  kNoPattern,   // Eq 9 from distance and speed only (pattern held at confronting)
  kOracle,      // Eq 9 fed the true nearest person (distance, speed, pattern)
};
constexpr std::array<Policy, 5> kPolicies = {Policy::kStrategy, Policy::kPlain, Policy::kStopAndWait,
                                             Policy::kNoPattern, Policy::kOracle};
const char* toString(Policy p);
/// The robot's speed policy a Policy runs with.
behavior::SpeedPolicy speedPolicy(Policy p);

/// Rows of the confusion matrix: the true pattern (behavior::Pattern order);
/// columns: the reported pattern, then "unseen" (the robot tracks nobody).
constexpr int kPatterns = 5;
constexpr int kUnseen = 5;
using Confusion = std::array<std::array<uint64_t, kPatterns + 1>, kPatterns>;

/// Where a false person was, seen from the robot, when it became a person:
/// in the camera's view at a distance its detector reaches (recall > 0), in
/// its view but nearer, beside the robot (outside the view, within 120 deg
/// of the heading), behind.
enum FalseWhereKind { kFalseInViewReached, kFalseInViewNear, kFalseBeside, kFalseBehind, kFalseWhereKinds };
using FalseWhere = std::array<uint32_t, kFalseWhereKinds>;
const char* falseWhereName(int k);

struct EpisodeMetrics {
  bool success = false;
  bool timeout = false;
  std::string failure;
  double time_to_goal_s = -1;
  double time_lost_s = -1;          // against the same episode without people (< 0: not completed)
  uint32_t robot_fault = 0;         // contacts with the robot moving towards the person
  uint32_t person_fault = 0;        // contacts with the robot standing or moving away
  uint32_t wall_collisions = 0;
  double min_gap_m = -1;            // body to body (0 = contact), < 0 = nobody ever present
  double intimate_s = 0;            // someone's body within 0.45 m of the robot's (Hall)
  double intimate_robot_s = 0;      // ...of which the robot was moving towards them (it could have avoided it)
  double personal_s = 0;            // ...within 1.2 m
  double path_m = 0;
  double irregularity_rad_m = 0;    // heading changes beyond the needed ones, per metre (HuNavSim)
  double max_jerk_m_s3 = 0;
  double duration_s = 0;
  Confusion confusion{};            // observable ticks: the nearest observable person within max avoidance
  int true_dominant = -1;           // most frequent true pattern other than none over those ticks (-1: none)
  int reported_dominant = -1;       // most frequent reported pattern other than none over them (-1: none)
  uint32_t false_people = 0;        // person tracks that appeared where nobody was (> 1 m from everyone)
  FalseWhere false_where{};         // ...by where they were when they became people
  uint32_t looks = 0;               // active looks started (the PTZ head turned to an undecided track)
  double ptz_off_path_s = 0;        // ...the time it pointed off the path (pan beyond its half field of view)
};

/// The robot's camera in the arena (experiments/scenarios/scenario_camera.hpp):
/// the detector model by default, `real` for the model's cross-check
/// (docs/scenarios.md, "The camera's cross-check"); off: the sonars alone.
using ArenaCamera = sim::ScenarioCamera;

/// Runs `e` with `p`. `reference_s` is the time to goal of the same episode
/// without people (time lost); `site_map` false runs the robot without its map.
/// `series` (may be null) receives the scenario runner's samples (plots).
EpisodeMetrics runEpisode(const Episode& e, const sim::ScenarioContext& ctx, Policy p, double reference_s,
                          const ArenaCamera& camera, bool site_map = true, sim::ScenarioRun* series = nullptr);

/// The reference run: nobody in the world, plain tracking (time to goal), and
/// the false people the robot tracks along the walls (with or without the map).
EpisodeMetrics runReference(const Episode& e, const sim::ScenarioContext& ctx, const ArenaCamera& camera,
                            bool site_map);

}  // namespace inspect::arena
