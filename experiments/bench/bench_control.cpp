// bench_control: cost of the control chain. (1) One call of the fuzzy-PID
// gain scheduler (Eq 15, the 49-rule config/fuzzy/fuzzy_pid.fis) evaluated
// directly (fuzzy::Engine) and compiled (fuzzy::LookupSurface), against the
// fuzzylite C++ library on the same .fis and inputs in the same run.
// (2) Closed-loop speed of the circle experiment (sim/closed_loop.hpp):
// simulated seconds per wall second, PID and fuzzy-PID. Not a test; the
// timing method is bench_fuzzy's (warm-up, repetitions, median).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shared/config/control_config.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/control/fuzzy_pid.hpp"
#include "shared/fuzzy/fis_error.hpp"
#include "shared/fuzzy/fis_reader.hpp"
#include "shared/util/cli_args.hpp"
#include "sim/closed_loop.hpp"
#include "tests/support/paths.hpp"

#ifdef INSPECT_HAVE_FUZZYLITE
#include <fl/Headers.h>
#endif

namespace {

using Clock = std::chrono::steady_clock;
using namespace inspect;

constexpr const char* kUsage =
    "usage: bench_control [--reps N] [--quick] [--json FILE] [--robot FILE] [--control FILE]\n"
    "Times the fuzzy-PID gain scheduler (direct engine, lookup surface, fuzzylite) per call and\n"
    "the closed-loop circle experiment (simulated s per wall s, PID and fuzzy-PID); prints a\n"
    "table, --json also writes the figures. Defaults: the repository's config/robot.yaml and\n"
    "config/control.yaml (whose fuzzy_pid.fis is the one timed), 7 repetitions, median.\n";

struct Timing {
  std::string name;
  double median = 0;  // per call (ns) or per run (s)
  double min = 0;
  long calls_per_rep = 0;
};

// Warm-up, then `reps` timed passes of `calls` calls; median and minimum ns per call.
Timing timePerCall(const std::string& name, long calls, int reps, const std::function<double(std::size_t)>& body,
                   std::size_t n_inputs) {
  double acc = 0;
  for (long i = 0; i < std::min<long>(calls / 10 + 1, 20000); ++i) acc += body(static_cast<std::size_t>(i) % n_inputs);
  std::vector<double> ns;
  for (int r = 0; r < reps; ++r) {
    const auto t0 = Clock::now();
    for (long i = 0; i < calls; ++i) acc += body(static_cast<std::size_t>(i) % n_inputs);
    ns.push_back(std::chrono::duration<double, std::nano>(Clock::now() - t0).count() / static_cast<double>(calls));
  }
  volatile double sink = acc;  // keeps the work observable
  (void)sink;
  std::sort(ns.begin(), ns.end());
  return {name, ns[ns.size() / 2], ns.front(), calls};
}

double sumGains(const control::PidGains& g) { return g.kp + g.ki + g.kd; }

nlohmann::ordered_json numberOrNull(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}

struct LoopCase {
  std::string name;
  control::WheelControl wc;
  std::shared_ptr<control::FuzzyGainScheduler> sched;
};

struct LoopTiming {
  std::string name;
  double sim_s = 0;
  double wall_median_s = 0;
  double wall_min_s = 0;
  long ticks = 0;
};

/// (2) The closed-loop circle experiment (the track_experiment defaults, no
/// samples kept) with the PID and the fuzzy-PID on either scheduler.
std::vector<LoopTiming> timeClosedLoops(const config::RobotConfig& robot, const config::ControlConfig& ctl,
                                        const std::shared_ptr<control::FuzzyGainScheduler>& lookup,
                                        const std::shared_ptr<control::FuzzyGainScheduler>& direct, int reps) {
  const std::vector<LoopCase> cases{{"circle, PID", control::WheelControl::kPid, nullptr},
                                    {"circle, fuzzy-PID (lookup)", control::WheelControl::kFuzzyPid, lookup},
                                    {"circle, fuzzy-PID (direct)", control::WheelControl::kFuzzyPid, direct}};
  std::vector<LoopTiming> loops;
  double checksum = 0;  // keeps the runs observable
  for (const auto& c : cases) {
    sim::ClosedLoopConfig cfg;
    cfg.robot = robot;
    cfg.tracker = ctl.tracker;
    cfg.tracker.wheel_control = c.wc;
    auto once = [&] { return sim::runClosedLoop(cfg, control::makeCircle({0, 0, 0}, 3.5, 0.5), c.sched, false); };
    const auto warm = once();
    std::vector<double> wall;
    for (int r = 0; r < reps; ++r) {
      const auto t0 = Clock::now();
      const auto res = once();
      wall.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
      checksum += res.metrics.max_pos_err_m;
    }
    std::sort(wall.begin(), wall.end());
    volatile double sink = checksum;
    (void)sink;
    loops.push_back({c.name, warm.metrics.duration_s, wall[wall.size() / 2], wall.front(),
                     std::lround(warm.metrics.duration_s / cfg.control_dt_s)});
  }
  return loops;
}

/// (1)'s figures: the scheduler's timings and how far the methods differ.
struct SchedulerFigures {
  std::string fis_shown;
  std::size_t rules = 0;
  int reps = 0;
  std::vector<Timing> sched;
  double direct_ns = 0, fl_ns = 0, lookup_err = 0, fl_err = 0;
  std::string fl_name;
};

void printTables(const SchedulerFigures& figures, const std::vector<LoopTiming>& loops) {
  const auto& [fis_shown, rules, reps, sched, direct_ns, fl_ns, lookup_err, fl_err, fl_name] = figures;
  std::printf("bench_control: %s (%zu rules), %d repetitions, median\n\n", fis_shown.c_str(), rules,
              reps);
  std::printf("Fuzzy-PID gain scheduler (Eq 15), one call = scale e/ec, infer kpx/kix/kdx, form kp/ki/kd\n");
  std::printf("%-56s %10s %10s %12s %14s\n", "method", "ns/call", "min ns", "vs direct", "vs fuzzylite");
  for (const auto& t : sched) {
    std::printf("%-56s %10.1f %10.1f %11.2fx", t.name.c_str(), t.median, t.min, direct_ns / t.median);
    if (std::isfinite(fl_ns))
      std::printf(" %13.2fx\n", fl_ns / t.median);
    else
      std::printf(" %14s\n", "-");
  }
  std::printf("'vs X' = X's time / this time (how many times faster than X).\n");
  std::printf("max |gain difference| lookup vs direct: %.4g; ", lookup_err);
  if (std::isfinite(fl_err))
    std::printf("fuzzylite vs direct: %.4g (centroid sampling: 101 points vs fuzzylite's 100)\n", fl_err);
  else
    std::printf("%s\n", fl_name.c_str());

  std::printf("\nClosed loop, circle r 3.5 m at 0.5 m/s, control dt 0.01 s, plant dt 0.001 s, noise on\n");
  std::printf("%-34s %10s %12s %12s %14s %12s\n", "run", "sim s", "wall ms", "min wall ms", "sim s/wall s",
              "us/tick");
  for (const auto& l : loops)
    std::printf("%-34s %10.2f %12.3f %12.3f %14.0f %12.3f\n", l.name.c_str(), l.sim_s, l.wall_median_s * 1e3,
                l.wall_min_s * 1e3, l.sim_s / l.wall_median_s, l.wall_median_s * 1e6 / static_cast<double>(l.ticks));
  std::printf("us/tick = wall time per 0.01 s control tick, including 10 plant steps and the noise model.\n");

}

/// The same figures as JSON (--json); false (printed why) when the file cannot be written.
bool writeJson(const std::string& json_path, const SchedulerFigures& figures, const std::vector<LoopTiming>& loops) {
  const auto& [fis_shown, rules, reps, sched, direct_ns, fl_ns, lookup_err, fl_err, fl_name] = figures;
  nlohmann::ordered_json j;
  j["fis"] = fis_shown;
  j["rules"] = rules;
  j["repetitions"] = reps;
  auto& js = j["scheduler"];
  js = nlohmann::ordered_json::array();
  for (const auto& t : sched)
    js.push_back({{"method", t.name},
                  {"ns_per_call_median", t.median},
                  {"ns_per_call_min", t.min},
                  {"calls_per_repetition", t.calls_per_rep},
                  {"speedup_vs_direct", direct_ns / t.median},
                  {"speedup_vs_fuzzylite", numberOrNull(fl_ns / t.median)}});
  j["max_gain_diff_lookup_vs_direct"] = lookup_err;
  j["max_gain_diff_fuzzylite_vs_direct"] = numberOrNull(fl_err);
  auto& jl = j["closed_loop"];
  jl = nlohmann::ordered_json::array();
  for (const auto& l : loops)
    jl.push_back({{"run", l.name},
                  {"simulated_s", l.sim_s},
                  {"wall_s_median", l.wall_median_s},
                  {"wall_s_min", l.wall_min_s},
                  {"simulated_s_per_wall_s", l.sim_s / l.wall_median_s},
                  {"us_per_control_tick", l.wall_median_s * 1e6 / static_cast<double>(l.ticks)}});
  std::ofstream f(json_path);
  f << j.dump(2) << "\n";
  if (!f) {
    std::fprintf(stderr, "bench_control: cannot write %s\n", json_path.c_str());
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::string robot_path = inspect::test::srcPath("config/robot.yaml");
  std::string control_path = inspect::test::srcPath("config/control.yaml");
  std::string json_path;
  int reps = 7;
  bool quick = false;
  cli::readOrExit("bench_control", argc, argv, [&](cli::ArgReader& a) {
    if (a.isHelp()) {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else if (a.is("--reps")) {
      reps = static_cast<int>(a.integer(1, 1000000));
    } else if (a.is("--json")) {
      json_path = a.path();
    } else if (a.is("--robot")) {
      robot_path = a.path();
    } else if (a.is("--control")) {
      control_path = a.path();
    } else if (a.is("--quick")) {
      quick = true;
    } else {
      a.unknown();
    }
  });

  config::TrackingSetup loaded;
  try {
    loaded = config::loadTrackingSetup(robot_path, control_path);
  } catch (const std::runtime_error& e) {  // ConfigError, FisError
    std::fprintf(stderr, "bench_control: %s\n", e.what());
    return 2;
  }
  const config::RobotConfig& robot = loaded.robot;
  const config::ControlConfig& ctl = loaded.control;
  const fuzzy::Fis& fis = loaded.fis;
  const control::FuzzyPidParams& p = ctl.tracker.fuzzy;
  const std::string fis_shown = std::filesystem::path(ctl.fis_path).lexically_normal().string();
  auto direct = std::make_shared<control::FuzzyGainScheduler>(fis, false);
  auto lookup = std::make_shared<control::FuzzyGainScheduler>(fis, true);

  // Raw (e, ec) over the region the scaled universes cover: the wheel loop's
  // own inputs, in rad/s and rad/s^2 (fixed pseudo-random, same for all).
  constexpr std::size_t kInputs = 4096;
  std::vector<double> e(kInputs), ec(kInputs);
  std::uint64_t state = 0x9E3779B97F4A7C15ull;
  auto uniform = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) / 9007199254740992.0;
  };
  for (std::size_t k = 0; k < kInputs; ++k) {
    e[k] = (2 * uniform() - 1) * fis.inputs[0].max / p.ke;
    ec[k] = (2 * uniform() - 1) * fis.inputs[1].max / p.kec;
  }

  // (1) Scheduler per call.
  const long scale = quick ? 10 : 1;
  std::vector<Timing> sched;
  sched.push_back(timePerCall("scheduler, direct (fuzzy::Engine, 101 samples)", 40000 / scale, reps,
                              [&](std::size_t k) { return sumGains(direct->gains(p, e[k], ec[k])); }, kInputs));
  sched.push_back(timePerCall("scheduler, compiled (fuzzy::LookupSurface, 201x201)", 4000000 / scale, reps,
                              [&](std::size_t k) { return sumGains(lookup->gains(p, e[k], ec[k])); }, kInputs));
  double lookup_err = 0;
  for (std::size_t k = 0; k < kInputs; ++k) {
    const auto a = direct->gains(p, e[k], ec[k]), b = lookup->gains(p, e[k], ec[k]);
    lookup_err = std::max({lookup_err, std::abs(a.kp - b.kp), std::abs(a.ki - b.ki), std::abs(a.kd - b.kd)});
  }
  double fl_err = std::nan("");
  std::string fl_name = "fuzzylite: not built in (install libfuzzylite-dev and re-run cmake)";
#ifdef INSPECT_HAVE_FUZZYLITE
  std::unique_ptr<fl::Engine> fle;
  try {
    fl::FisImporter importer;
    fle.reset(importer.fromFile(ctl.fis_path));
  } catch (const std::exception& ex) {
    std::fprintf(stderr, "bench_control: fuzzylite cannot import %s: %s\n", ctl.fis_path.c_str(), ex.what());
    return 2;
  }
  std::string status;
  if (!fle->isReady(&status)) {
    std::fprintf(stderr, "bench_control: fuzzylite engine not ready: %s\n", status.c_str());
    return 2;
  }
  fl::InputVariable* fl_e = fle->getInputVariable(0);
  fl::InputVariable* fl_ec = fle->getInputVariable(1);
  fl::OutputVariable* fl_out[3] = {fle->getOutputVariable(0), fle->getOutputVariable(1), fle->getOutputVariable(2)};
  // The same work as FuzzyGainScheduler::gains: scale, saturate, infer, Eq 15.
  auto flGains = [&](std::size_t k) {
    fl_e->setValue(std::clamp(p.ke * e[k], fis.inputs[0].min, fis.inputs[0].max));
    fl_ec->setValue(std::clamp(p.kec * ec[k], fis.inputs[1].min, fis.inputs[1].max));
    fle->process();
    return control::PidGains{std::max(0.0, p.base.kp + p.k1 * fl_out[0]->getValue()),
                             std::max(0.0, p.base.ki + p.k2 * fl_out[1]->getValue()),
                             std::max(0.0, p.base.kd + p.k3 * fl_out[2]->getValue())};
  };
  fl_name = "scheduler, fuzzylite " + fl::fuzzylite::version() + " (same .fis)";
  sched.push_back(timePerCall(fl_name, 4000 / scale, reps, [&](std::size_t k) { return sumGains(flGains(k)); },
                              kInputs));
  fl_err = 0;
  for (std::size_t k = 0; k < kInputs; k += 3) {
    const auto a = direct->gains(p, e[k], ec[k]), b = flGains(k);
    fl_err = std::max({fl_err, std::abs(a.kp - b.kp), std::abs(a.ki - b.ki), std::abs(a.kd - b.kd)});
  }
#endif
  const double direct_ns = sched[0].median;
  const double fl_ns = sched.size() > 2 ? sched[2].median : std::nan("");

  const std::vector<LoopTiming> loops = timeClosedLoops(robot, ctl, lookup, direct, reps);
  const SchedulerFigures figures{fis_shown, fis.rules.size(), reps, sched, direct_ns, fl_ns, lookup_err, fl_err, fl_name};
  printTables(figures, loops);
  if (!json_path.empty() && !writeJson(json_path, figures, loops)) return 1;
  return 0;
}
