// social_arena: the randomized social-navigation arena (docs/scenarios.md,
// "The arena"). Generates episodes from a seed, runs each with five policies
// and a reference without people on two threads, and prints per policy the
// social-navigation benchmarks' figures, the confusion of reported vs true
// pattern, false people with and without the site map; writes a Pareto plot,
// the worst episodes' plots, JSON and a per-episode CSV
// (social_arena_report.cpp); --cross-check compares the detector model with
// the real camera (social_arena_cross_check.cpp).
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "experiments/arena/social_arena_parts.hpp"
#include "shared/util/cli_args.hpp"

using namespace inspect;
using namespace inspect::arena_cli;
using arena::Policy;

namespace {

const char* kUsage = R"(usage: social_arena [options]
Runs the social-navigation arena (docs/scenarios.md, "The arena"): episodes
generated from a seed (aisles and crossings of several widths, 1-3 people at
0.3-1.6 m/s, crossing angles 30-150 deg, behaviours regular / not reacting /
stop-and-go / two together), each with five policies (strategy, plain_tracking,
stop_and_wait, no_pattern, oracle) and a reference run without people, in
sim time with the robot's decision core over the serial codec.
  --episodes N            episodes (default 500)
  --seed N                run seed (default 1); episode K of seed S is always the same
  --episode K             run only episode K (with --print-world: print its world file)
  --print-world           print the world file of --episode K and exit
  --threads N             worker threads (default 2)
  --worst N               plot the N worst episodes of the strategy (default 3; needs --plots)
  --plots DIR             write DIR/pareto.png and DIR/arena_<k>.png
  --json FILE             every figure as JSON
  --csv FILE              one row per episode and policy
  --robot-config FILE     default config/robot.yaml
  --control-config FILE   default config/control.yaml
  --behavior-config FILE  default config/behavior.yaml
  --camera model|real|none  the robot's camera people detections: drawn from the detector
                          model calibrated on bench_people (default), the simulator's camera
                          rendered and the robot's detector run on it (about 70 ms a picture),
                          or none (sonars alone)
  --heads both|ptz        the camera heads: the PTZ head and, when the robot config has a
                          wide_camera, the wide fixed one (default both), or the PTZ head alone
  --cross-check N         the model against the real camera and detector on episodes 0..N-1
                          (strategy and the two references, each camera): a table of both
                          figures, their difference and the stated margin (docs/scenarios.md)
  --active-look on|off    the PTZ head turned to undecided sonar tracks beside the robot
                          (config/behavior.yaml active_look.enabled; default: the config's)
  --crossings             the eight crossing cases instead of the episodes: 45 and 135 degrees,
                          1.4 and 0.4 m/s, a walker who yields and one who does not; what the
                          robot reports on the observable crossing ticks (docs/scenarios.md)
  --quiet                 no progress bar
  --help                  print this help
Exit status: 0 when the run finished (the targets are reported, not enforced),
2 on a usage or configuration error.
)";

[[noreturn]] void usageError(const std::string& msg) {
  std::fprintf(stderr, "social_arena: %s\n", msg.c_str());
  std::exit(2);
}

Options parse(int argc, char** argv) {
  Options o;
  try {
    cli::ArgReader a(argc, argv);
    while (a.next()) {
      if (a.isHelp()) {
        std::fputs(kUsage, stdout);
        std::exit(0);
      } else if (a.is("--episodes")) {
        o.episodes = static_cast<int>(a.integer(1, 100000));
      } else if (a.is("--seed")) {
        o.seed = static_cast<uint64_t>(a.integer(0, 4294967295LL));
      } else if (a.is("--episode")) {
        o.only = static_cast<int>(a.integer(0, 100000));
      } else if (a.is("--print-world")) {
        o.print_world = true;
      } else if (a.is("--threads")) {
        o.threads = static_cast<int>(a.integer(1, 64));
      } else if (a.is("--worst")) {
        o.worst = static_cast<int>(a.integer(0, 100));
      } else if (a.is("--plots")) {
        o.plots = a.path();
      } else if (a.is("--json")) {
        o.json = a.path();
      } else if (a.is("--csv")) {
        o.csv = a.path();
      } else if (a.is("--robot-config")) {
        o.robot = a.path();
      } else if (a.is("--control-config")) {
        o.control = a.path();
      } else if (a.is("--behavior-config")) {
        o.behavior = a.path();
      } else if (a.is("--camera")) {
        const std::string c = a.choice({"model", "real", "none"});
        o.camera.enabled = c != "none";
        o.camera.real = c == "real";
      } else if (a.is("--heads")) {
        o.camera.wide_head = a.choice({"both", "ptz"}) == "both";
      } else if (a.is("--cross-check")) {
        o.cross_check = static_cast<int>(a.integer(1, 10000));
      } else if (a.is("--active-look")) {
        o.active_look = a.choice({"on", "off"}) == "on" ? 1 : 0;
      } else if (a.is("--crossings")) {
        o.crossings = true;
      } else if (a.is("--quiet")) {
        o.quiet = true;
      } else {
        a.unknown();
      }
    }
  } catch (const cli::UsageError& e) {
    usageError(e.what());
  }
  if (o.print_world && o.only < 0) usageError("--print-world needs --episode K");
  if (o.crossings && (o.only >= 0 || o.cross_check)) usageError("--crossings runs its own cases: not with --episode or --cross-check");
  if (o.cross_check && (o.only >= 0 || !o.camera.enabled || o.camera.real))
    usageError("--cross-check compares the model with the real camera: not with --episode or --camera real|none");
  return o;
}

/// Every episode with the five policies and the two references, on
/// o.threads threads with a progress bar; nullopt (printed why) when one failed.
std::optional<std::vector<EpisodeResult>> runEpisodes(const Options& o, const std::vector<int>& indices,
                                                      const std::vector<sim::ScenarioContext>& contexts,
                                                      double& wall_s) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<EpisodeResult> results(indices.size());
  std::atomic<std::size_t> next{0}, done{0};
  std::mutex err_mu;
  std::string error;
  auto worker = [&](int tid) {
    const auto& ctx = contexts[static_cast<std::size_t>(tid)];
    for (std::size_t i = next++; i < indices.size(); i = next++) {
      try {
        EpisodeResult r;
        r.episode = arena::generateEpisode(o.seed, indices[i]);
        r.reference = arena::runReference(r.episode, ctx, o.camera, true);
        r.reference_no_map = arena::runReference(r.episode, ctx, o.camera, false);
        for (std::size_t k = 0; k < kP; ++k)
          r.by_policy[k] = arena::runEpisode(r.episode, ctx, arena::kPolicies[k], r.reference.time_to_goal_s, o.camera);
        results[i] = std::move(r);
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lk(err_mu);
        if (error.empty()) error = "episode " + std::to_string(indices[i]) + ": " + e.what();
      }
      ++done;
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < o.threads; ++t) pool.emplace_back(worker, t);
  const bool bar = !o.quiet && isatty(STDERR_FILENO);
  while (done.load() < indices.size()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    const std::size_t d = done.load();
    const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!o.quiet) {
      const int width = 40, fill = static_cast<int>(width * d / indices.size());
      std::fprintf(stderr, "%s[%s%s] %zu/%zu episodes, %.0f s%s", bar ? "\r" : "", std::string(fill, '#').c_str(),
                   std::string(width - fill, '.').c_str(), d, indices.size(), el, bar ? "" : "\n");
      std::fflush(stderr);
      if (!bar) std::this_thread::sleep_for(std::chrono::seconds(5));
    }
  }
  for (auto& t : pool) t.join();
  if (bar) std::fputc('\n', stderr);
  if (!error.empty()) {
    std::fprintf(stderr, "social_arena: %s\n", error.c_str());
    return std::nullopt;
  }
  wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return results;

}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  if (o.print_world) {
    std::fputs(arena::worldYaml(arena::generateEpisode(o.seed, o.only)).c_str(), stdout);
    return 0;
  }
  std::vector<int> indices;
  if (o.only >= 0) indices.push_back(o.only);
  else
    for (int k = 0; k < o.episodes; ++k) indices.push_back(k);

  std::vector<sim::ScenarioContext> contexts;
  try {
    for (int t = 0; t < o.threads; ++t) {
      contexts.push_back(sim::loadScenarioContext(o.robot, o.control, o.behavior));
      if (o.active_look >= 0) contexts.back().awareness.active_look.enabled = o.active_look == 1;
    }
  } catch (const std::exception& e) {
    usageError(e.what());
  }

  if (o.cross_check) return crossCheck(o, contexts);
  if (o.crossings) return crossings(o, contexts);

  double wall_s = 0;
  const auto results = runEpisodes(o, indices, contexts, wall_s);
  if (!results) return 2;
  report(o, *results, contexts, wall_s);
  return 0;
}
