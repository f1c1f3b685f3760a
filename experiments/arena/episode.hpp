#pragma once
// The social-navigation arena's episodes (docs/scenarios.md, "The arena"):
// from a run seed and an episode number, a world (an aisle, or two aisles
// crossing at an angle, of a drawn width), 1-3 people with drawn speeds,
// angles, offsets, start times and behaviours, and the robot's task (a line
// along its aisle at 0.5 m/s). Pure and reproducible: the same seed and
// number give the same episode on every machine (the draws use the
// generator's raw 64-bit output, not a standard distribution).
#include <cstdint>
#include <string>
#include <vector>

#include "experiments/scenarios/scenario.hpp"

namespace inspect::arena {

/// How a generated person behaves.
enum class Behaviour {
  kRegular,      // the social force model: gives the robot room, sidesteps
  kNotReacting,  // distracted or carrying something: keeps their line past the robot (only contact stops them)
  kStopAndGo,    // regular, but stands still for a while near the robot's path
  kTogether,     // two people walking side by side (counted as two people)
};
const char* toString(Behaviour b);

enum class Layout { kAisle, kCrossing };
const char* toString(Layout l);

struct GeneratedPerson {
  std::string id;
  Behaviour behaviour = Behaviour::kRegular;
  double speed_m_s = 0.5;
  double heading_deg = 0.0;  // walking direction relative to the robot's aisle (0 = same as the robot)
};

struct Episode {
  uint64_t run_seed = 1;
  int index = 0;
  uint64_t seed = 0;          // the episode's own seed (from run_seed and index)
  Layout layout = Layout::kAisle;
  double width_m = 3.0;       // the robot's aisle
  double cross_width_m = 0;   // the cross aisle (crossing layout)
  double cross_angle_deg = 0; // angle of the cross aisle to the robot's aisle
  std::vector<GeneratedPerson> people;  // parallel to spec.world.pedestrians
  sim::ScenarioSpec spec;     // world, task, time limit
};

/// Episode `index` of the run seeded `run_seed`. Throws config::ConfigError
/// only on a bug (every generated world is validated by the world reader).
Episode generateEpisode(uint64_t run_seed, int index);

/// The crossing set (issue 61): one person crossing the robot's path at an
/// angle (45 or 135 degrees to its heading), fast (1.4 m/s) or slow
/// (0.4 m/s), yielding (the social force model) or not (keeps their line),
/// timed to reach the crossing point when the robot would; a 3.0 m aisle
/// and a 2.4 m cross aisle meeting 5 m ahead, the task a 9 m line.
struct CrossingCase {
  double angle_deg = 45.0;
  double speed_m_s = 1.4;
  bool yields = true;
  std::string name() const;  // e.g. "cross45_fast_yields"
};
/// The eight cases: 45 / 135 degrees x fast / slow x yields / does not.
std::vector<CrossingCase> crossingCases();
Episode crossingEpisode(const CrossingCase& c);

/// The episode as a world file (docs/world-format.md): `mcu_sim --world` and
/// loadWorldText read it back to the same world.
std::string worldYaml(const Episode& e);

}  // namespace inspect::arena
