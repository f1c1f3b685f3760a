// bench_tuning: speed of the fuzzy-PID tuner (pc_server/tuning/tuner.hpp).
// (1) Closed-loop runs per second and evaluations per second (the default
// scenarios: plant variations x seeds) with 1 thread and with N threads, and
// the speed-up. (2) One full tuning run (the defaults: circle, max_evals
// evaluations, N threads) from the paper's gains: wall time, initial and best
// cost. --compare runs (2) once per global algorithm with the same budget.
// Not a test; the ctest smoke entry runs --quick.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "pc_server/tuning/tuner.hpp"
#include "shared/config/config_node.hpp"
#include "shared/config/control_config.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/fuzzy/fis_error.hpp"
#include "shared/fuzzy/fis_reader.hpp"
#include "sim/robot_plant.hpp"
#include "shared/util/cli_args.hpp"
#include "tests/support/paths.hpp"

namespace {

using Clock = std::chrono::steady_clock;
using namespace inspect;

constexpr const char* kUsage =
    "usage: bench_tuning [--evals N] [--threads N] [--quick] [--plant nominal|worn] [--compare]\n"
    "                    [--global ALG] [--local ALG] [--variations N] [--seeds N] [--json FILE]\n"
    "                    [--robot FILE] [--control FILE]\n"
    "Times the tuner: closed-loop runs/s and evaluations/s with 1 and N threads, then a full\n"
    "tuning run (default 1000 evaluations, circle, 2 threads, the TuneSetup defaults) from the\n"
    "paper's gains: wall time, initial and best cost. --plant worn tunes for a worn robot (wheel\n"
    "gains 0.85/0.95, time constants 0.32/0.28 s, dead time 0.04 s). --compare repeats the tuning\n"
    "with each global algorithm (GN_CRS2_LM, GN_ISRES, GN_DIRECT_L). --quick: a few seconds.\n"
    "--json FILE also writes the figures.\n";

struct Rate {
  int threads = 0;
  int evals = 0;
  int runs = 0;
  double wall_s = 0;
  double cpu_s = 0;  // process CPU time (all threads)
  double runsPerS() const { return runs / wall_s; }
  double evalsPerS() const { return evals / wall_s; }
};

struct Tuning {
  std::string algorithm;
  tuning::TuneResult result;
  double cpu_s = 0;
};

double cpuSeconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

Rate measureRate(tuning::TuneSetup setup, int threads, int evals, const control::GainSet& g) {
  setup.threads = threads;
  const tuning::Tuner tuner(setup);
  double sink = tuner.evaluate(g).cost;  // warm-up
  const auto t0 = Clock::now();
  const double c0 = cpuSeconds();
  int scenarios = 0;
  for (int i = 0; i < evals; ++i) {
    const auto e = tuner.evaluate(g);
    sink += e.cost;
    scenarios = e.scenarios;
  }
  Rate r{threads, evals, evals * scenarios, std::chrono::duration<double>(Clock::now() - t0).count(),
         cpuSeconds() - c0};
  volatile double keep = sink;
  (void)keep;
  return r;
}

nlohmann::ordered_json gainsJson(const control::GainSet& g) {
  nlohmann::ordered_json j;
  for (const char* name : control::kGainNames) j[name] = control::gainValue(g, name);
  return j;
}

/// Throughput and the tuning runs, for people.
void printTables(const tuning::TuneSetup& setup, const std::string& plant_name, int hw, const std::vector<Rate>& rates,
                 const std::vector<Tuning>& tunings, int evals, int threads) {
  std::printf("bench_tuning: %s, plant %s, %d variation(s) x %d seed(s) = %d runs per evaluation, %d hardware threads\n\n",
              setup.reference.describe().c_str(), plant_name.c_str(), setup.plant_variations, setup.seeds,
              setup.plant_variations * setup.seeds, hw);
  std::printf("Throughput (evaluations of the paper's gains, fuzzy-PID, lookup surface)\n");
  std::printf("%-10s %10s %10s %10s %12s %12s %10s\n", "threads", "evals", "wall s", "cpu s", "runs/s", "evals/s",
              "speed-up");
  for (const auto& r : rates)
    std::printf("%-10d %10d %10.3f %10.3f %12.1f %12.2f %9.2fx\n", r.threads, r.evals, r.wall_s, r.cpu_s, r.runsPerS(),
                r.evalsPerS(), r.runsPerS() / rates.front().runsPerS());
  std::printf("cpu s = CPU time of the process over all threads: on an idle machine wall ~ cpu / threads.\n");
  std::printf("\nTuning from the paper's gains, %d evaluations max, %d thread(s), global share %.2f\n", evals, threads,
              setup.global_fraction);
  std::printf("%-28s %8s %10s %10s %12s %12s %12s\n", "algorithm", "evals", "wall s", "cpu s", "initial cost",
              "best cost", "improvement");
  for (const auto& t : tunings) {
    const auto& r = t.result;
    std::printf("%-28s %8d %10.2f %10.2f %12.3f %12.3f %11.1f%%\n", t.algorithm.c_str(), r.evals, r.wall_s, t.cpu_s,
                r.initial_eval.cost, r.best_eval.cost, 100.0 * (1.0 - r.best_eval.cost / r.initial_eval.cost));
  }
  const auto& best = std::min_element(tunings.begin(), tunings.end(), [](const Tuning& a, const Tuning& b) {
                       return a.result.best_eval.cost < b.result.best_eval.cost;
                     })->result;
  std::printf("best gains (%s):", best.algorithm.c_str());
  for (const char* name : control::kGainNames) std::printf(" %s %.4g", name, control::gainValue(best.best, name));
  std::printf("\nnominal run with them: max pos %.4f m, max ang %.4f rad, conv pos %.2f s, conv ang %.2f s "
              "(paper gains: %.4f m, %.4f rad, %.2f s, %.2f s)\n",
              best.best_eval.nominal.max_pos_err_m, best.best_eval.nominal.max_ang_err_rad,
              best.best_eval.nominal.converge_pos_s, best.best_eval.nominal.converge_ang_s,
              best.initial_eval.nominal.max_pos_err_m, best.initial_eval.nominal.max_ang_err_rad,
              best.initial_eval.nominal.converge_pos_s, best.initial_eval.nominal.converge_ang_s);
}

/// The same figures as JSON (--json); false (printed why) when the file cannot be written.
bool writeJson(const std::string& json_path, const tuning::TuneSetup& setup, const std::string& plant_name, int hw, const std::vector<Rate>& rates,
                 const std::vector<Tuning>& tunings, int evals, int threads) {
  nlohmann::ordered_json j;
  j["reference"] = setup.reference.describe();
  j["plant"] = plant_name;
  j["plant_variations"] = setup.plant_variations;
  j["seeds"] = setup.seeds;
  j["runs_per_evaluation"] = setup.plant_variations * setup.seeds;
  j["hardware_threads"] = hw;
  auto& jr = j["throughput"];
  jr = nlohmann::ordered_json::array();
  for (const auto& r : rates)
    jr.push_back({{"threads", r.threads},
                  {"evaluations", r.evals},
                  {"wall_s", r.wall_s},
                  {"cpu_s", r.cpu_s},
                  {"runs_per_s", r.runsPerS()},
                  {"evaluations_per_s", r.evalsPerS()},
                  {"speedup", r.runsPerS() / rates.front().runsPerS()}});
  auto& jt = j["tuning"];
  jt = nlohmann::ordered_json::array();
  for (const auto& t : tunings)
    jt.push_back({{"algorithm", t.algorithm},
                  {"max_evals", evals},
                  {"threads", threads},
                  {"evaluations", t.result.evals},
                  {"wall_s", t.result.wall_s},
                  {"cpu_s", t.cpu_s},
                  {"initial_cost", t.result.initial_eval.cost},
                  {"best_cost", t.result.best_eval.cost},
                  {"improvement", 1.0 - t.result.best_eval.cost / t.result.initial_eval.cost},
                  {"best_gains", gainsJson(t.result.best)}});
  std::ofstream f(json_path);
  f << j.dump(2) << "\n";
  if (!f) {
    std::fprintf(stderr, "bench_tuning: cannot write %s\n", json_path.c_str());
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::string robot_path = inspect::test::srcPath("config/robot.yaml");
  std::string control_path = inspect::test::srcPath("config/control.yaml");
  std::string json_path, plant_name = "nominal";
  int evals = -1, threads = 2, variations = -1, seeds = -1;
  bool quick = false, compare = false;
  std::string global_alg, local_alg;
  cli::readOrExit("bench_tuning", argc, argv, [&](cli::ArgReader& a) {
    constexpr int64_t kMany = 10000000;
    if (a.isHelp()) {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else if (a.is("--evals")) {
      evals = static_cast<int>(a.integer(10, kMany));
    } else if (a.is("--threads")) {
      threads = static_cast<int>(a.integer(1, kMany));
    } else if (a.is("--variations")) {
      variations = static_cast<int>(a.integer(1, kMany));
    } else if (a.is("--seeds")) {
      seeds = static_cast<int>(a.integer(1, kMany));
    } else if (a.is("--quick")) {
      quick = true;
    } else if (a.is("--compare")) {
      compare = true;
    } else if (a.is("--plant")) {
      plant_name = a.choice({"nominal", "worn"});
    } else if (a.is("--global")) {
      global_alg = a.path();
    } else if (a.is("--local")) {
      local_alg = a.path();
    } else if (a.is("--json")) {
      json_path = a.path();
    } else if (a.is("--robot")) {
      robot_path = a.path();
    } else if (a.is("--control")) {
      control_path = a.path();
    } else {
      a.unknown();
    }
  });
  if (evals < 0) evals = quick ? 40 : 1000;

  tuning::TuneSetup setup;
  try {
    auto loaded = config::loadTrackingSetup(robot_path, control_path);
    setup.robot = std::move(loaded.robot);
    setup.control = std::move(loaded.control);
    setup.fis = std::move(loaded.fis);
  } catch (const std::runtime_error& e) {  // ConfigError, FisError
    std::fprintf(stderr, "bench_tuning: %s\n", e.what());
    return 2;
  }
  setup.plant = sim::nominalPlant(setup.robot);
  if (plant_name == "worn") {
    setup.plant.left.gain = 0.85;
    setup.plant.right.gain = 0.95;
    setup.plant.left.time_constant_s = 0.32;
    setup.plant.right.time_constant_s = 0.28;
    setup.plant.left.dead_time_s = setup.plant.right.dead_time_s = 0.04;
  }
  if (variations > 0) setup.plant_variations = variations;
  if (seeds > 0) setup.seeds = seeds;
  if (!global_alg.empty()) setup.global_algorithm = global_alg;
  if (!local_alg.empty()) setup.local_algorithm = local_alg;
  setup.max_evals = evals;
  setup.threads = threads;
  control::GainSet start;
  start.fuzzy = setup.control.tracker.fuzzy;
  start.aux = setup.control.tracker.aux;

  std::vector<Rate> rates;
  std::vector<Tuning> tunings;
  try {
    // (1) Throughput: evaluations of the paper's gains.
    const int rate_evals = quick ? 3 : 20;
    rates.push_back(measureRate(setup, 1, rate_evals, start));
    if (threads > 1) rates.push_back(measureRate(setup, threads, rate_evals, start));

    // (2) Tuning runs.
    std::vector<std::string> globals{setup.global_algorithm};
    if (compare) globals = {"GN_CRS2_LM", "GN_ISRES", "GN_DIRECT_L"};
    for (const auto& g : globals) {
      tuning::TuneSetup s = setup;
      s.global_algorithm = g;
      tuning::Tuner tuner(s);
      const double c0 = cpuSeconds();
      Tuning t{g, tuner.run(start, {}, nullptr)};
      t.cpu_s = cpuSeconds() - c0;
      t.algorithm = t.result.algorithm;
      tunings.push_back(std::move(t));
    }
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "bench_tuning: %s\n", e.what());
    return 2;
  }

  const int hw = static_cast<int>(std::thread::hardware_concurrency());
  printTables(setup, plant_name, hw, rates, tunings, evals, threads);
  if (!json_path.empty() && !writeJson(json_path, setup, plant_name, hw, rates, tunings, evals, threads)) return 1;
  return 0;
}
