// social_arena --cross-check (docs/scenarios.md, "The camera's cross-check"):
// the strategy and the two references on episodes 0..N-1, once with the
// detector model and once with the simulator's camera rendered and the
// robot's detector run on it; both figures, their difference and the
// stated margin.
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <thread>

#include "experiments/arena/social_arena_parts.hpp"

namespace inspect::arena_cli {

using arena::Policy;

namespace {

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

/// Both cameras' runs of every episode, the thread time each took, the wall time.
struct CheckResults {
  std::vector<std::array<CheckRun, 2>> runs;
  std::array<double, 2> busy_s{};  // CPU time per camera, summed over the threads
  double wall_s = 0;
  std::string error;  // the first episode that failed ("" = none)
};

CheckResults runChecks(const Options& o, const std::vector<sim::ScenarioContext>& contexts,
                       const arena::ArenaCamera& model, const arena::ArenaCamera& real) {
  const int n = o.cross_check;
  CheckResults res;
  res.runs.resize(static_cast<std::size_t>(n));
  auto& runs = res.runs;
  std::atomic<int> next{0}, done{0};
  std::mutex err_mu;
  std::string error;
  auto& busy_s = res.busy_s;
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
  res.error = error;
  res.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  return res;
}

/// The figures of both cameras, as the full arena reports them, with their margins.
std::vector<CheckRow> checkRows(const std::vector<std::array<CheckRun, 2>>& runs, int n) {
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
  return rows;
}

}  // namespace

int crossCheck(const Options& o, const std::vector<sim::ScenarioContext>& contexts) {
  arena::ArenaCamera model = o.camera, real = o.camera;
  model.real = false;
  real.real = true;
  const int n = o.cross_check;
  const CheckResults res = runChecks(o, contexts, model, real);
  if (!res.error.empty()) {
    std::fprintf(stderr, "social_arena: %s\n", res.error.c_str());
    return 2;
  }
  const double wall_s = res.wall_s;
  const auto& busy_s = res.busy_s;
  const std::vector<CheckRow> rows = checkRows(res.runs, n);
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
  if (o.json.empty()) return 0;
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
  return 0;
}

}  // namespace inspect::arena_cli
