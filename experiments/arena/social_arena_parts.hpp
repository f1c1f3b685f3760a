#pragma once
// social_arena's parts (experiments/arena/social_arena.cpp runs the episodes;
// social_arena_report.cpp prints, plots and writes their figures;
// social_arena_cross_check.cpp compares the detector model with the real
// camera; social_arena_crossings.cpp runs the crossing cases): its options, one episode's results, a policy's summary.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "experiments/arena/arena_run.hpp"

namespace inspect::arena_cli {

struct Options {
  int episodes = 500;
  uint64_t seed = 1;
  int only = -1;
  bool print_world = false;
  int threads = 2;
  int worst = 3;
  std::string plots, json, csv;
  std::string robot = "config/robot.yaml", control = "config/control.yaml", behavior = "config/behavior.yaml";
  bool quiet = false;
  arena::ArenaCamera camera;
  int cross_check = 0;
  bool crossings = false;
  int active_look = -1;  // -1: config/behavior.yaml's active_look.enabled; 0 off, 1 on
};

constexpr std::size_t kP = arena::kPolicies.size();

struct EpisodeResult {
  arena::Episode episode;
  arena::EpisodeMetrics reference;         // nobody, plain tracking, with the map
  arena::EpisodeMetrics reference_no_map;  // nobody, without the map (false people along walls)
  std::array<arena::EpisodeMetrics, kP> by_policy;
};

// Per policy, over all episodes.
struct Summary {
  int episodes = 0, success = 0, timeouts = 0, completed = 0;
  uint32_t robot_fault = 0, person_fault = 0, robot_fault_episodes = 0, person_fault_episodes = 0;
  int intimate_episodes = 0, intimate_robot_episodes = 0;
  double intimate_robot_s = 0;
  double intimate_s = 0, personal_s = 0, time_lost_s = 0, irregularity = 0, jerk = 0, min_gap_sum = 0;
  double min_gap = 1e9;
  int gap_n = 0;
  std::vector<double> lost;
  arena::Confusion confusion{};
  int dominant_n = 0, dominant_right = 0;
  uint32_t false_people = 0;
  double minutes = 0;
  double meanLost() const { return completed ? time_lost_s / completed : 0; }
  double meanPersonal() const { return episodes ? personal_s / episodes : 0; }
};

struct Accuracy {
  uint64_t ticks = 0, right = 0, seen = 0, seen_right = 0;
};

Summary summarize(const std::vector<EpisodeResult>& rs, std::size_t k);
Accuracy accuracy(const arena::Confusion& c);
double ratio(uint64_t a, uint64_t b);
std::string patternName(int k);

/// Every table of a run for people, then its plots (--plots), CSV (--csv)
/// and JSON (--json); contexts[0] replays the worst episodes for their plots.
void report(const Options& o, const std::vector<EpisodeResult>& results,
            const std::vector<sim::ScenarioContext>& contexts, double wall_s);
/// --cross-check: the detector model against the real camera and detector
/// on episodes 0..N-1; 0, or 2 when an episode failed.
int crossCheck(const Options& o, const std::vector<sim::ScenarioContext>& contexts);
/// --crossings: the eight crossing cases (arena::crossingCases) with the
/// strategy and the oracle; 0, or 2 when a case failed.
int crossings(const Options& o, const std::vector<sim::ScenarioContext>& contexts);

}  // namespace inspect::arena_cli
