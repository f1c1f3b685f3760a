// social_arena: the randomized social-navigation arena (docs/scenarios.md,
// "The arena"). Generates episodes from a seed, runs each with five policies
// and a reference without people on two threads, and prints per policy the
// social-navigation benchmarks' figures, the confusion of reported vs true
// pattern, false people with and without the site map; writes a Pareto plot,
// the worst episodes' plots, JSON and a per-episode CSV.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <numeric>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "experiments/arena/arena_run.hpp"
#include "shared/util/cli_args.hpp"
#include "shared/util/gnuplot.hpp"

using namespace inspect;
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
  --cross-check N         the model against the real camera and detector on episodes 0..N-1
                          (strategy and the two references, each camera): a table of both
                          figures, their difference and the stated margin (docs/scenarios.md)
  --quiet                 no progress bar
  --help                  print this help
Exit status: 0 when the run finished (the targets are reported, not enforced),
2 on a usage or configuration error.
)";

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
};

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
      } else if (a.is("--cross-check")) {
        o.cross_check = static_cast<int>(a.integer(1, 10000));
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
  if (o.cross_check && (o.only >= 0 || !o.camera.enabled || o.camera.real))
    usageError("--cross-check compares the model with the real camera: not with --episode or --camera real|none");
  return o;
}

constexpr std::size_t kP = arena::kPolicies.size();

struct EpisodeResult {
  arena::Episode episode;
  arena::EpisodeMetrics reference;         // nobody, plain tracking, with the map
  arena::EpisodeMetrics reference_no_map;  // nobody, without the map (false people along walls)
  std::array<arena::EpisodeMetrics, kP> by_policy;
};

std::string patternName(int k) {
  return k == arena::kUnseen ? "unseen" : std::string(behavior::toString(static_cast<behavior::Pattern>(k)));
}

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

Summary summarize(const std::vector<EpisodeResult>& rs, std::size_t k) {
  Summary s;
  for (const auto& r : rs) {
    const auto& m = r.by_policy[k];
    ++s.episodes;
    s.success += m.success ? 1 : 0;
    s.timeouts += m.timeout ? 1 : 0;
    s.robot_fault += m.robot_fault;
    s.person_fault += m.person_fault;
    s.robot_fault_episodes += m.robot_fault > 0 ? 1 : 0;
    s.person_fault_episodes += m.person_fault > 0 ? 1 : 0;
    s.intimate_s += m.intimate_s;
    s.intimate_episodes += m.intimate_s > 0 ? 1 : 0;
    s.intimate_robot_s += m.intimate_robot_s;
    s.intimate_robot_episodes += m.intimate_robot_s > 0 ? 1 : 0;
    s.personal_s += m.personal_s;
    s.irregularity += m.irregularity_rad_m;
    s.jerk += m.max_jerk_m_s3;
    if (m.min_gap_m >= 0) {
      s.min_gap = std::min(s.min_gap, m.min_gap_m);
      s.min_gap_sum += m.min_gap_m;
      ++s.gap_n;
    }
    if (m.time_lost_s > -1e8 && m.time_to_goal_s >= 0 && r.reference.time_to_goal_s >= 0) {
      ++s.completed;
      s.time_lost_s += m.time_lost_s;
      s.lost.push_back(m.time_lost_s);
    }
    for (int a = 0; a < arena::kPatterns; ++a)
      for (int b = 0; b <= arena::kPatterns; ++b) s.confusion[a][b] += m.confusion[a][b];
    if (m.true_dominant > 0) {
      ++s.dominant_n;
      s.dominant_right += m.reported_dominant == m.true_dominant ? 1 : 0;
    }
    s.false_people += m.false_people;
    s.minutes += m.duration_s / 60.0;
  }
  std::sort(s.lost.begin(), s.lost.end());
  return s;
}

double ratio(uint64_t a, uint64_t b) { return b ? static_cast<double>(a) / static_cast<double>(b) : 0.0; }

struct Accuracy {
  uint64_t ticks = 0, right = 0, seen = 0, seen_right = 0;
};
Accuracy accuracy(const arena::Confusion& c) {
  Accuracy a;
  for (int t = 0; t < arena::kPatterns; ++t)
    for (int r = 0; r <= arena::kPatterns; ++r) {
      a.ticks += c[t][r];
      if (r != arena::kUnseen) a.seen += c[t][r];
      if (r == t) {
        a.right += c[t][r];
        a.seen_right += c[t][r];
      }
    }
  return a;
}

double percentile(const std::vector<double>& v, double q) {
  if (v.empty()) return 0;
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5))];
}

void printConfusion(const arena::Confusion& c, const char* title) {
  std::printf("\n%s (rows: true pattern, columns: reported; ticks)\n", title);
  std::printf("%-13s", "true \\ rep");
  for (int r = 0; r <= arena::kPatterns; ++r) std::printf(" %12s", patternName(r).c_str());
  std::printf(" %8s\n", "right");
  for (int t = 0; t < arena::kPatterns; ++t) {
    uint64_t row = 0;
    for (int r = 0; r <= arena::kPatterns; ++r) row += c[t][r];
    std::printf("%-13s", patternName(t).c_str());
    for (int r = 0; r <= arena::kPatterns; ++r) std::printf(" %12llu", static_cast<unsigned long long>(c[t][r]));
    std::printf(" %7.1f%%\n", 100.0 * ratio(c[t][t], row));
  }
}

nlohmann::ordered_json confusionJson(const arena::Confusion& c) {
  nlohmann::ordered_json j;
  for (int t = 0; t < arena::kPatterns; ++t) {
    nlohmann::ordered_json row;
    for (int r = 0; r <= arena::kPatterns; ++r) row[patternName(r)] = c[t][r];
    j[patternName(t)] = row;
  }
  return j;
}

// How bad an episode went for a policy (for "worst"): robot-at-fault
// contacts first, then intimate time the robot caused, then any, a timeout, the smallest gap.
double badness(const arena::EpisodeMetrics& m) {
  return 1e6 * m.robot_fault + 100.0 * m.intimate_robot_s + m.intimate_s + (m.timeout ? 50.0 : 0.0) +
         (m.min_gap_m >= 0 ? 2.0 - std::min(2.0, m.min_gap_m) : 0.0);
}

std::string plotPareto(const std::string& path, const std::array<Summary, kP>& sums) {
  plot::Panel p = plot::panel("arena: time lost vs personal-zone time (mean per episode, one point per policy)",
                              "time lost (s)", "personal-zone time (s)");
  const char* colors[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e"};
  for (std::size_t k = 0; k < kP; ++k) {
    plot::Series s = plot::series(arena::toString(arena::kPolicies[k]), colors[k]);
    s.style = "points pt 7 ps 2";
    s.x = {sums[k].meanLost()};
    s.y = {sums[k].meanPersonal()};
    p.series.push_back(s);
    p.labels.push_back({sums[k].meanLost(), sums[k].meanPersonal(), std::string("  ") + arena::toString(arena::kPolicies[k]),
                        colors[k]});
  }
  p.key = "outside right";
  return plot::renderPng(path, {p}, 900, 500);
}


// --- the camera's cross-check (docs/scenarios.md, "The camera's cross-check") ---

/// One episode's figures with one camera: the strategy and the two references.
struct CheckRun {
  arena::EpisodeMetrics strategy, reference, reference_no_map;
};

/// A figure of the cross-check: both values, their difference and whether it is within the margin.
struct CheckRow {
  const char* name;
  double model = 0, real = 0;
  double margin = 0;
  bool relative = false;  // the margin is a share of the model's value
  const char* unit = "";
  bool within() const { return std::fabs(real - model) <= (relative ? margin * std::fabs(model) : margin) + 1e-12; }
};

int crossCheck(const Options& o, const std::vector<sim::ScenarioContext>& contexts) {
  arena::ArenaCamera model = o.camera, real = o.camera;
  model.real = false;
  real.real = true;
  const int n = o.cross_check;
  std::vector<std::array<CheckRun, 2>> runs(static_cast<std::size_t>(n));
  std::atomic<int> next{0}, done{0};
  std::mutex err_mu;
  std::string error;
  std::array<double, 2> busy_s{};  // CPU time per camera, summed over the threads
  std::mutex busy_mu;
  const auto t0 = std::chrono::steady_clock::now();
  auto worker = [&](int tid) {
    const auto& ctx = contexts[static_cast<std::size_t>(tid)];
    for (int i = next++; i < n; i = next++) {
      try {
        const arena::Episode e = arena::generateEpisode(o.seed, i);
        for (int c = 0; c < 2; ++c) {
          const auto& cam = c == 0 ? model : real;
          const auto c0 = std::chrono::steady_clock::now();
          CheckRun& r = runs[static_cast<std::size_t>(i)][static_cast<std::size_t>(c)];
          r.reference = arena::runReference(e, ctx, cam, true);
          r.reference_no_map = arena::runReference(e, ctx, cam, false);
          r.strategy = arena::runEpisode(e, ctx, Policy::kStrategy, r.reference.time_to_goal_s, cam);
          std::lock_guard lk(busy_mu);
          busy_s[static_cast<std::size_t>(c)] += std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count();
        }
      } catch (const std::exception& ex) {
        std::lock_guard lk(err_mu);
        if (error.empty()) error = "episode " + std::to_string(i) + ": " + ex.what();
      }
      const int d = ++done;
      if (!o.quiet)
        std::fprintf(stderr, "cross-check: %d/%d episodes, %.0f s\n", d, n,
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < o.threads; ++t) pool.emplace_back(worker, t);
  for (auto& t : pool) t.join();
  if (!error.empty()) {
    std::fprintf(stderr, "social_arena: %s\n", error.c_str());
    return 2;
  }
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  // Aggregates per camera, as the full arena reports them.
  struct Agg {
    arena::Confusion confusion{};
    int dominant_n = 0, dominant_right = 0, robot_fault_episodes = 0, completed = 0;
    double personal_s = 0, lost_s = 0, minutes = 0, min_map = 0, min_nomap = 0;
    uint32_t false_people = 0, false_map = 0, false_nomap = 0;
  };
  std::array<Agg, 2> agg;
  for (const auto& pair : runs)
    for (int c = 0; c < 2; ++c) {
      const CheckRun& r = pair[static_cast<std::size_t>(c)];
      Agg& a = agg[static_cast<std::size_t>(c)];
      const auto& m = r.strategy;
      for (int t = 0; t < arena::kPatterns; ++t)
        for (int k = 0; k <= arena::kPatterns; ++k) a.confusion[t][k] += m.confusion[t][k];
      if (m.true_dominant > 0) {
        ++a.dominant_n;
        a.dominant_right += m.reported_dominant == m.true_dominant ? 1 : 0;
      }
      a.robot_fault_episodes += m.robot_fault > 0 ? 1 : 0;
      a.personal_s += m.personal_s;
      if (m.time_lost_s > -1e8 && m.time_to_goal_s >= 0 && r.reference.time_to_goal_s >= 0) {
        ++a.completed;
        a.lost_s += m.time_lost_s;
      }
      a.false_people += m.false_people;
      a.minutes += m.duration_s / 60.0;
      a.false_map += r.reference.false_people;
      a.min_map += r.reference.duration_s / 60.0;
      a.false_nomap += r.reference_no_map.false_people;
      a.min_nomap += r.reference_no_map.duration_s / 60.0;
    }
  const auto acc = [&](int c) {
    const Accuracy a = accuracy(agg[static_cast<std::size_t>(c)].confusion);
    return 100.0 * ratio(a.right, a.ticks);
  };
  const auto per = [](double x, double d) { return d > 0 ? x / d : 0.0; };
  std::vector<CheckRow> rows = {
      {"pattern right, observable ticks", acc(0), acc(1), 5.0, false, "%"},
      {"dominant pattern right", 100.0 * ratio(static_cast<uint64_t>(agg[0].dominant_right), static_cast<uint64_t>(agg[0].dominant_n)),
       100.0 * ratio(static_cast<uint64_t>(agg[1].dominant_right), static_cast<uint64_t>(agg[1].dominant_n)), 10.0, false, "%"},
      {"false people, no map", per(agg[0].false_nomap, agg[0].min_nomap), per(agg[1].false_nomap, agg[1].min_nomap), 0.2, true, "/min"},
      {"false people, with map", per(agg[0].false_map, agg[0].min_map), per(agg[1].false_map, agg[1].min_map), 0.1, false, "/min"},
      {"false people, with people", per(agg[0].false_people, agg[0].minutes), per(agg[1].false_people, agg[1].minutes), 0.25, true, "/min"},
      {"robot-fault contact episodes", static_cast<double>(agg[0].robot_fault_episodes), static_cast<double>(agg[1].robot_fault_episodes), 2.0, false, ""},
      {"time lost, mean", per(agg[0].lost_s, agg[0].completed), per(agg[1].lost_s, agg[1].completed), 0.15, true, "s"},
      {"personal-zone time, mean", agg[0].personal_s / n, agg[1].personal_s / n, 0.15, true, "s"},
  };
  std::printf("social_arena --cross-check: seed %llu, episodes 0-%d, strategy and references with the detector model "
              "and with the real camera (%dx%d, %s, noise %.1f, exposure %.0f ms) at %.1f Hz; %.0f s on %d threads "
              "(model %.0f s, real %.0f s of thread time)\n\n",
              static_cast<unsigned long long>(o.seed), n - 1, real.width, real.height,
              perception::describe(real.detector).c_str(), real.noise_sigma, real.exposure_ms, real.rate_hz, wall_s,
              o.threads, busy_s[0], busy_s[1]);
  std::printf("%-32s %10s %10s %10s %12s %7s\n", "figure", "model", "real", "real-model", "margin", "agree");
  int agree = 0;
  for (const auto& r : rows) {
    char margin[32];
    std::snprintf(margin, sizeof margin, r.relative ? "+-%.0f%%" : "+-%.2g", r.relative ? 100 * r.margin : r.margin);
    std::printf("%-32s %9.2f%-1s %9.2f%-1s %+10.2f %12s %7s\n", r.name, r.model, r.unit[0] == '%' ? "%" : "", r.real,
                r.unit[0] == '%' ? "%" : "", r.real - r.model, margin, r.within() ? "yes" : "NO");
    agree += r.within() ? 1 : 0;
  }
  std::printf("\n%d of %zu figures within their margins (units: %% of ticks or episodes, people per minute, episodes, "
              "seconds per episode; relative margins are shares of the model's value)\n",
              agree, rows.size());
  if (!o.json.empty()) {
    nlohmann::ordered_json j;
    j["seed"] = o.seed;
    j["episodes"] = n;
    j["wall_s"] = wall_s;
    j["threads"] = o.threads;
    j["thread_s"] = {{"model", busy_s[0]}, {"real", busy_s[1]}};
    j["detector"] = perception::describe(real.detector);
    for (const auto& r : rows)
      j["figures"][r.name] = {{"model", r.model}, {"real", r.real}, {"margin", r.margin},
                              {"margin_relative", r.relative}, {"unit", r.unit}, {"agree", r.within()}};
    j["agree"] = agree;
    std::ofstream f(o.json);
    f << j.dump(2) << "\n";
    if (!f) std::fprintf(stderr, "social_arena: cannot write %s\n", o.json.c_str());
  }
  return 0;
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
    for (int t = 0; t < o.threads; ++t) contexts.push_back(sim::loadScenarioContext(o.robot, o.control, o.behavior));
  } catch (const std::exception& e) {
    usageError(e.what());
  }

  if (o.cross_check) return crossCheck(o, contexts);

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
    return 2;
  }
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  // --- episode mix ---
  int aisles = 0, people = 0;
  std::array<int, 4> behaviours{};
  for (const auto& r : results) {
    aisles += r.episode.layout == arena::Layout::kAisle ? 1 : 0;
    people += static_cast<int>(r.episode.people.size());
    for (const auto& p : r.episode.people) ++behaviours[static_cast<std::size_t>(p.behaviour)];
  }
  std::printf("social_arena: seed %llu, %zu episodes (%d aisle, %zu crossing), %d people (regular %d, not reacting %d, "
              "stop-and-go %d, together %d), %zu runs in %.1f s on %d threads\n",
              static_cast<unsigned long long>(o.seed), results.size(), aisles, results.size() - aisles, people,
              behaviours[0], behaviours[1], behaviours[2], behaviours[3], results.size() * (kP + 2), wall_s, o.threads);

  std::array<Summary, kP> sums;
  for (std::size_t k = 0; k < kP; ++k) sums[k] = summarize(results, k);

  std::printf("\n%-15s %7s %6s %11s %12s %8s %9s %9s %9s %9s %9s %9s %8s %8s\n", "policy", "success", "tmout",
              "robot-fault", "person-fault", "min gap", "mean gap", "intim s", "intim ep", "robot ep", "pers s",
              "lost s", "irreg", "jerk");
  for (std::size_t k = 0; k < kP; ++k) {
    const auto& s = sums[k];
    std::printf("%-15s %6.1f%% %6d %5u (%3u ep) %6u (%3u ep) %8.2f %9.2f %9.2f %9d %9d %9.2f %9.2f %8.3f %8.2f\n",
                arena::toString(arena::kPolicies[k]), 100.0 * ratio(static_cast<uint64_t>(s.success), static_cast<uint64_t>(s.episodes)),
                s.timeouts, s.robot_fault, s.robot_fault_episodes, s.person_fault, s.person_fault_episodes,
                s.gap_n ? s.min_gap : 0.0, s.gap_n ? s.min_gap_sum / s.gap_n : 0.0,
                s.episodes ? s.intimate_s / s.episodes : 0.0, s.intimate_episodes, s.intimate_robot_episodes,
                s.meanPersonal(), s.meanLost(),
                s.episodes ? s.irregularity / s.episodes : 0.0, s.episodes ? s.jerk / s.episodes : 0.0);
  }
  std::printf("(per episode means; intim: someone's body within 0.45 m of the robot's, ep: episodes with any, robot ep:\n"
              " with the robot moving towards them while there; min gap body to body over all episodes; lost: mean over completed episodes, "
              "against the same episode without people; irreg rad/m; jerk: max per episode, m/s^3)\n");

  const Accuracy acc = accuracy(sums[0].confusion);
  printConfusion(sums[0].confusion, "strategy: reported vs true pattern on observable ticks");
  std::printf("pattern accuracy: %.1f%% of %llu observable ticks (%.1f%% of the %llu the robot tracked someone); "
              "dominant pattern right in %d of %d episodes (%.1f%%)\n",
              100.0 * ratio(acc.right, acc.ticks), static_cast<unsigned long long>(acc.ticks),
              100.0 * ratio(acc.seen_right, acc.seen), static_cast<unsigned long long>(acc.seen), sums[0].dominant_right,
              sums[0].dominant_n, 100.0 * ratio(static_cast<uint64_t>(sums[0].dominant_right), static_cast<uint64_t>(sums[0].dominant_n)));

  uint32_t false_map = 0, false_nomap = 0;
  double min_map = 0, min_nomap = 0;
  arena::FalseWhere where_nomap{}, where_people{};
  for (const auto& r : results) {
    false_map += r.reference.false_people;
    min_map += r.reference.duration_s / 60.0;
    false_nomap += r.reference_no_map.false_people;
    min_nomap += r.reference_no_map.duration_s / 60.0;
    for (int k = 0; k < arena::kFalseWhereKinds; ++k) {
      where_nomap[static_cast<std::size_t>(k)] += r.reference_no_map.false_where[static_cast<std::size_t>(k)];
      where_people[static_cast<std::size_t>(k)] += r.by_policy[0].false_where[static_cast<std::size_t>(k)];
    }
  }
  std::printf("\nfalse people (nobody in the world, driving the aisles): with the site map %u in %.1f min "
              "(%.3f/min), without %u in %.1f min (%.3f/min); with people, strategy: %u in %.1f min\n",
              false_map, min_map, min_map > 0 ? false_map / min_map : 0.0, false_nomap, min_nomap,
              min_nomap > 0 ? false_nomap / min_nomap : 0.0, sums[0].false_people, sums[0].minutes);
  std::printf("false people by where they were (the camera's view: +-hfov/2 of the heading; reached: its detector's "
              "recall > 0 there)\n  %-18s %10s %18s\n", "where", "no map", "with people (strategy)");
  for (int k = 0; k < arena::kFalseWhereKinds; ++k)
    std::printf("  %-18s %10u %18u\n", arena::falseWhereName(k), where_nomap[static_cast<std::size_t>(k)],
                where_people[static_cast<std::size_t>(k)]);

  const auto& st = sums[0];
  const auto& sw = sums[2];
  const auto& orc = sums[4];
  std::printf("\nstrategy vs stop_and_wait: time lost %.2f vs %.2f s, personal-zone %.2f vs %.2f s; vs oracle: "
              "time lost %+.0f%%, personal-zone %+.0f%%\n",
              st.meanLost(), sw.meanLost(), st.meanPersonal(), sw.meanPersonal(),
              orc.meanLost() > 0 ? 100.0 * (st.meanLost() / orc.meanLost() - 1) : 0.0,
              orc.meanPersonal() > 0 ? 100.0 * (st.meanPersonal() / orc.meanPersonal() - 1) : 0.0);

  // Worst episodes of the strategy.
  std::vector<std::size_t> order(results.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return badness(results[a].by_policy[0]) > badness(results[b].by_policy[0]); });
  const std::size_t worst_n = std::min<std::size_t>(static_cast<std::size_t>(std::max(o.worst, 0)), order.size());
  std::printf("\nworst episodes of the strategy (replay: social_arena --seed %llu --episode K; world: --print-world):\n",
              static_cast<unsigned long long>(o.seed));
  for (std::size_t w = 0; w < std::min<std::size_t>(std::max<std::size_t>(worst_n, 5), order.size()); ++w) {
    const auto& r = results[order[w]];
    const auto& m = r.by_policy[0];
    std::string who;
    for (const auto& p : r.episode.people)
      who += (who.empty() ? "" : ", ") + std::string(arena::toString(p.behaviour)) + " " +
             std::to_string(static_cast<int>(std::lround(p.heading_deg))) + " deg";
    std::printf("  K=%-4d %-8s w %.1f m: robot-fault %u, person-fault %u, intimate %.2f s, min gap %.2f m, %s [%s]\n",
                r.episode.index, arena::toString(r.episode.layout), r.episode.width_m, m.robot_fault, m.person_fault,
                m.intimate_s, m.min_gap_m, m.success ? "ok" : m.failure.c_str(), who.c_str());
  }

  if (!o.plots.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(o.plots, ec);
    std::string err = plotPareto(o.plots + "/pareto.png", sums);
    for (std::size_t w = 0; w < worst_n && err.empty(); ++w) {
      const auto& r = results[order[w]];
      std::vector<sim::ScenarioRun> runs;
      for (Policy p : {Policy::kStrategy, Policy::kPlain, Policy::kStopAndWait}) {
        sim::ScenarioRun run;
        (void)arena::runEpisode(r.episode, contexts[0], p, r.reference.time_to_goal_s, o.camera, true, &run);
        runs.push_back(std::move(run));
      }
      err = sim::plotScenario(o.plots, r.episode.spec, runs);
    }
    if (!err.empty()) std::fprintf(stderr, "social_arena: plots: %s\n", err.c_str());
    else std::printf("plots in %s (pareto.png, arena_<K>.png)\n", o.plots.c_str());
  }

  if (!o.csv.empty()) {
    std::ofstream f(o.csv);
    f << "episode,seed,layout,width_m,cross_angle_deg,people,behaviours,policy,success,timeout,robot_fault,"
         "person_fault,min_gap_m,intimate_s,intimate_robot_s,personal_s,time_to_goal_s,time_lost_s,irregularity_rad_m,max_jerk_m_s3,"
         "observable_ticks,right_ticks,true_dominant,reported_dominant,false_people\n";
    for (const auto& r : results) {
      std::string beh;
      for (const auto& p : r.episode.people) beh += (beh.empty() ? "" : ";") + std::string(arena::toString(p.behaviour));
      for (std::size_t k = 0; k < kP; ++k) {
        const auto& m = r.by_policy[k];
        const Accuracy a = accuracy(m.confusion);
        char line[640];
        std::snprintf(line, sizeof line, "%d,%llu,%s,%.1f,%.1f,%zu,%s,%s,%d,%d,%u,%u,%.3f,%.2f,%.2f,%.2f,%.2f,%.2f,%.4f,%.2f,%llu,%llu,%s,%s,%u\n",
                      r.episode.index, static_cast<unsigned long long>(r.episode.seed), arena::toString(r.episode.layout),
                      r.episode.width_m, r.episode.cross_angle_deg, r.episode.people.size(), beh.c_str(),
                      arena::toString(arena::kPolicies[k]), m.success ? 1 : 0, m.timeout ? 1 : 0, m.robot_fault,
                      m.person_fault, m.min_gap_m, m.intimate_s, m.intimate_robot_s, m.personal_s, m.time_to_goal_s, m.time_lost_s,
                      m.irregularity_rad_m, m.max_jerk_m_s3, static_cast<unsigned long long>(a.ticks),
                      static_cast<unsigned long long>(a.right), m.true_dominant > 0 ? patternName(m.true_dominant).c_str() : "",
                      m.reported_dominant > 0 ? patternName(m.reported_dominant).c_str() : "", m.false_people);
        f << line;
      }
    }
    if (!f) std::fprintf(stderr, "social_arena: cannot write %s\n", o.csv.c_str());
  }

  if (!o.json.empty()) {
    nlohmann::ordered_json j;
    j["seed"] = o.seed;
    j["episodes"] = results.size();
    j["wall_s"] = wall_s;
    j["threads"] = o.threads;
    for (std::size_t k = 0; k < kP; ++k) {
      const auto& s = sums[k];
      nlohmann::ordered_json p;
      p["success"] = s.success;
      p["timeouts"] = s.timeouts;
      p["robot_fault_collisions"] = s.robot_fault;
      p["robot_fault_episodes"] = s.robot_fault_episodes;
      p["person_fault_collisions"] = s.person_fault;
      p["person_fault_episodes"] = s.person_fault_episodes;
      p["min_gap_m"] = s.gap_n ? s.min_gap : 0.0;
      p["mean_min_gap_m"] = s.gap_n ? s.min_gap_sum / s.gap_n : 0.0;
      p["intimate_s_mean"] = s.episodes ? s.intimate_s / s.episodes : 0.0;
      p["intimate_episodes"] = s.intimate_episodes;
      p["intimate_robot_s_mean"] = s.episodes ? s.intimate_robot_s / s.episodes : 0.0;
      p["intimate_robot_episodes"] = s.intimate_robot_episodes;
      p["personal_s_mean"] = s.meanPersonal();
      p["time_lost_s_mean"] = s.meanLost();
      p["time_lost_s_p90"] = percentile(s.lost, 0.9);
      p["irregularity_rad_m_mean"] = s.episodes ? s.irregularity / s.episodes : 0.0;
      p["max_jerk_m_s3_mean"] = s.episodes ? s.jerk / s.episodes : 0.0;
      const Accuracy a = accuracy(s.confusion);
      p["pattern_accuracy"] = ratio(a.right, a.ticks);
      p["pattern_accuracy_tracked"] = ratio(a.seen_right, a.seen);
      p["dominant_right"] = s.dominant_right;
      p["dominant_episodes"] = s.dominant_n;
      p["false_people"] = s.false_people;
      p["minutes"] = s.minutes;
      p["confusion"] = confusionJson(s.confusion);
      j["policies"][arena::toString(arena::kPolicies[k])] = p;
    }
    j["false_people"] = {{"with_map", false_map},       {"with_map_min", min_map},
                         {"without_map", false_nomap}, {"without_map_min", min_nomap}};
    for (int k = 0; k < arena::kFalseWhereKinds; ++k) {
      j["false_people"]["without_map_where"][arena::falseWhereName(k)] = where_nomap[static_cast<std::size_t>(k)];
      j["false_people"]["strategy_where"][arena::falseWhereName(k)] = where_people[static_cast<std::size_t>(k)];
    }
    std::ofstream f(o.json);
    f << j.dump(2) << "\n";
    if (!f) std::fprintf(stderr, "social_arena: cannot write %s\n", o.json.c_str());
  }
  return 0;
}
