#pragma once
// The scenario suite (docs/scenarios.md): the robot's own decision core
// (shared/robot/robot_core: people tracking, pattern, Eq 9 speed strategy,
// trajectory tracking, navigation automaton) driven over the real serial
// codec by the simulator (world, pedestrians moved by the social force model,
// ultrasonic model, hub-motor plant, MCU emulator) in sim time, far faster
// than real time. Each run is measured the way social-navigation benchmarks
// measure: success, collisions, distances to people, proxemic zone times,
// time to goal, path length, jerk, mode switches, pattern accuracy, first
// detection and stop times.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "shared/behavior/human_awareness.hpp"
#include "shared/config/control_config.hpp"
#include "shared/config/robot_config.hpp"
#include "sim/world_names.hpp"

namespace inspect::sim {

/// What the robot is told to do (one console command's worth).
struct ScenarioTask {
  enum class Kind { kLine, kCircle, kGoTo };
  Kind kind = Kind::kLine;
  double length_m = 0.0;       // line
  double radius_m = 0.0;       // circle
  double laps = 1.0;           // circle
  double speed_m_s = 0.5;      // line, circle, goto (cruise)
  std::vector<std::pair<double, double>> points_m;  // goto, odometry frame
  std::string controller;      // track: "" = configured default
  std::string describe() const;
};

/// The paper's reported timings for a scenario (seconds; absent = not reported).
struct PaperTimings {
  std::optional<double> detect_s;           // robot first detects the person
  std::optional<double> enter_avoidance_s;  // person enters the max avoidance distance
  std::optional<double> stop_s;             // robot speed reaches zero
  std::optional<double> slowest_s;          // lowest speed (the paper's real-robot runs)
};

struct ScenarioSpec {
  std::string name;
  std::string description;
  std::string world_file;
  World world;
  ScenarioTask task;
  behavior::Pattern expect_pattern = behavior::Pattern::kNone;  // dominant pattern expected (none = any)
  double time_limit_s = 120.0;
  PaperTimings paper;
};

/// Reads a suite file (config/scenarios/suite.yaml); world paths are relative to it.
std::vector<ScenarioSpec> loadSuiteFile(const std::string& path);

/// Everything a run needs besides the scenario.
struct ScenarioContext {
  config::RobotConfig robot;
  config::ControlConfig control;
  std::shared_ptr<control::FuzzyGainScheduler> scheduler;  // may be null (fuzzy-PID tracking refused)
  behavior::AwarenessConfig awareness;
};

/// Loads robot, control (with the fuzzy-PID scheduler) and behaviour configs. Throws config::ConfigError.
ScenarioContext loadScenarioContext(const std::string& robot_yaml, const std::string& control_yaml,
                                    const std::string& behavior_yaml);

class Simulation;

/// Watches a run tick by tick (the arena's ground truth and oracle).
class RunObserver {
 public:
  virtual ~RunObserver() = default;
  /// Before the tick's sensor frame reaches the decision core (the oracle
  /// feeds the true nearest person to `aw` here).
  virtual void beforeFrame(const Simulation& /*sim*/, behavior::HumanAwareness& /*aw*/, double /*t_s*/) {}
  /// After the tick, with what the robot made of it.
  virtual void afterTick(const Simulation& /*sim*/, const behavior::HumanAwareness& /*aw*/, double /*t_s*/) {}
};

struct RunOptions {
  behavior::SpeedPolicy policy = behavior::SpeedPolicy::kFuzzy;
  bool people = true;       // false: the scenario without its pedestrians (reference for time lost)
  uint32_t seed = 1;
  bool keep_series = false;  // fill ScenarioRun::series (plots)
  RunObserver* observer = nullptr;
  bool site_map = true;      // false: the robot runs without the site map (every echo may be a person)
};

/// One 10 ms tick of a run, for plots.
struct RunSample {
  double t_s;
  double x_m, y_m, theta_rad;  // true robot pose
  double v_m_s;                // true forward speed
  double person_m;             // centre distance to the nearest person (truth), < 0 = nobody
  double detected_m;           // the robot's estimate of that distance, < 0 = nobody tracked
  double speed_factor;         // Eq 9 factor in force
  int pattern;                 // robot's pattern (behavior::Pattern)
  int truth_pattern;
};

/// One pedestrian's true path (10 Hz), for plots.
struct PersonTrack {
  std::string id;
  std::vector<double> t_s, x_m, y_m;
};

/// Figures of one run (definitions in docs/scenarios.md).
struct RunMetrics {
  bool success = false;
  std::string failure;            // why not, "" on success
  bool completed = false;         // the command was acknowledged COMPLETED
  uint64_t person_collisions = 0;
  uint64_t wall_collisions = 0;
  double min_person_m = -1;       // centre to centre, < 0 = nobody ever present
  double min_gap_m = -1;          // body to body (centre distance minus both radii)
  double intimate_s = 0;          // centre distance < 0.45 m
  double personal_s = 0;          // centre distance < 1.2 m
  double time_to_goal_s = -1;     // command to COMPLETED
  double path_length_m = 0;
  double time_lost_s = -1;        // time_to_goal - the same run without people
  double max_jerk_m_s3 = 0;       // from the true speed sampled every 0.1 s, after the first 3 s
  uint32_t mode_switches = 0;     // robot mode changes + navigation automaton switches
  uint32_t pattern_switches = 0;
  double pattern_accuracy = -1;   // robot pattern == truth pattern, over ticks the robot tracks a person
                                  // and the nearest person is within max avoidance (truth)
  std::string dominant_pattern;   // most frequent non-none pattern the robot reported
  double detect_s = -1;           // first tick the robot tracks a person
  double enter_avoidance_s = -1;  // a person first within max avoidance distance (truth)
  double stop_s = -1;             // first time the true speed falls below 0.02 m/s after moving
  double slowest_s = -1;          // time of the lowest true speed after the first detection (while moving on)
  double slowest_m_s = -1;        // that speed
  double min_speed_factor = 1;
  double duration_s = 0;          // sim time of the run
  uint64_t false_tracks = 0;      // tracks dropped unconfirmed (tracker counters)
  double visible_s = 0;           // a person within max avoidance was inside a sonar cone (truth)
  double missed_s = 0;            // ...and the robot tracked nobody
};

struct ScenarioRun {
  std::string scenario;
  behavior::SpeedPolicy policy;
  bool people = true;
  RunMetrics metrics;
  std::vector<RunSample> series;
  std::vector<PersonTrack> people_paths;
};

/// Runs one scenario with one policy. Throws config::ConfigError on a bad context.
ScenarioRun runScenario(const ScenarioSpec& spec, const ScenarioContext& ctx, const RunOptions& opt);

/// Writes `<dir>/<scenario>.png` (paths with time marks, speed, distance with zones) from runs of
/// one scenario (the first run's paths are drawn). Returns "" or what went wrong.
std::string plotScenario(const std::string& dir, const ScenarioSpec& spec, const std::vector<ScenarioRun>& runs);

}  // namespace inspect::sim
