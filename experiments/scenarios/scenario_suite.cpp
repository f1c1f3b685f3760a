// scenario_suite: runs every scenario of a suite file headless and faster than
// real time with the robot's strategy and two baselines, prints a table per
// scenario and the paper's timings next to ours, writes PNG plots and JSON.
// docs/scenarios.md describes the scenarios and every figure.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shared/util/cli_args.hpp"
#include "shared/config/config_node.hpp"
#include "experiments/scenarios/scenario.hpp"
#include "experiments/scenarios/scenario_camera.hpp"

using namespace inspect;

namespace {

const char* kUsage = R"(usage: scenario_suite [options]
Runs the scenario suite (docs/scenarios.md) in-process in sim time: for each
scenario the robot's decision core (robot_client) with the fuzzy speed
strategy and two baselines (plain tracking: people never change the speed;
stop-and-wait: stop while anyone is within the max avoidance distance), plus
a run without people as the reference for time lost.
  --suite FILE            suite file (default config/scenarios/suite.yaml)
  --only NAME[,NAME...]   run only these scenarios
  --policies LIST         comma-separated: fuzzy, none, stop_and_wait (default all three)
  --robot-config FILE     default config/robot.yaml
  --control-config FILE   default config/control.yaml
  --behavior-config FILE  default config/behavior.yaml
  --seed N                sensor-noise seed (default 1)
  --camera none|model|real  the robot's camera people detections (docs/scenarios.md, "Paper
                          timings"): none (the sonars alone, default), the detector model
                          calibrated on bench_people, or the rendered camera and HOG detector
  --plots DIR             write DIR/<scenario>.png (paths, speed, distance with zones)
  --json FILE             write every figure as JSON
  --help                  print this help
Exit status: 0 when the fuzzy strategy succeeds in every scenario run (completed,
no collision), 1 when it does not, 2 on a usage or configuration error.
)";

struct Options {
  std::string suite = "config/scenarios/suite.yaml";
  std::vector<std::string> only;
  std::vector<behavior::SpeedPolicy> policies = {behavior::SpeedPolicy::kFuzzy, behavior::SpeedPolicy::kNone,
                                                 behavior::SpeedPolicy::kStopAndWait};
  std::string robot = "config/robot.yaml";
  std::string control = "config/control.yaml";
  std::string behavior = "config/behavior.yaml";
  uint32_t seed = 1;
  std::string plots;
  std::string json;
  sim::ScenarioCamera camera = [] {
    sim::ScenarioCamera c;
    c.enabled = false;
    return c;
  }();
};

/// The camera's pictures for one run.
class CameraObserver final : public sim::RunObserver {
 public:
  CameraObserver(const sim::ScenarioSpec& s, const sim::ScenarioContext& ctx, const sim::ScenarioCamera& c, uint64_t seed)
      : looks_(s.world, ctx.robot, ctx.awareness, c, seed) {}
  void beforeFrame(const sim::Simulation& sim, behavior::HumanAwareness& aw, double t_s) override {
    looks_.beforeFrame(sim, aw, t_s);
  }

 private:
  sim::CameraLooks looks_;
};

[[noreturn]] void usageError(const std::string& msg) {
  std::fprintf(stderr, "scenario_suite: %s\n", msg.c_str());
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
      } else if (a.is("--suite")) {
        o.suite = a.path();
      } else if (a.is("--only")) {
        o.only = a.list();
      } else if (a.is("--policies")) {
        o.policies.clear();
        for (const auto& p : a.list()) {
          try {
            o.policies.push_back(behavior::parseSpeedPolicy(p));
          } catch (const std::invalid_argument& e) {
            a.fail(e.what());
          }
        }
      } else if (a.is("--robot-config")) {
        o.robot = a.path();
      } else if (a.is("--control-config")) {
        o.control = a.path();
      } else if (a.is("--behavior-config")) {
        o.behavior = a.path();
      } else if (a.is("--seed")) {
        o.seed = static_cast<uint32_t>(a.integer(0, 4294967295LL));
      } else if (a.is("--camera")) {
        const std::string c = a.choice({"none", "model", "real"});
        o.camera.enabled = c != "none";
        o.camera.real = c == "real";
      } else if (a.is("--plots")) {
        o.plots = a.path();
      } else if (a.is("--json")) {
        o.json = a.path();
      } else {
        a.unknown();
      }
    }
  } catch (const cli::UsageError& e) {
    usageError(e.what());
  }
  return o;
}

// A figure that may be negative; "-" when not finite.
std::string fmtSigned(double v, const char* f = "%.2f") {
  if (!std::isfinite(v)) return "-";
  char b[48];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// A figure where negative means "does not apply".
std::string fmt(double v, const char* f = "%.2f") { return v < 0 ? "-" : fmtSigned(v, f); }

nlohmann::ordered_json orNull(double v) { return v < 0 || !std::isfinite(v) ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(v); }

nlohmann::ordered_json toJson(const sim::RunMetrics& m) {
  return {{"success", m.success},
          {"failure", m.failure},
          {"completed", m.completed},
          {"person_collisions", m.person_collisions},
          {"wall_collisions", m.wall_collisions},
          {"min_person_distance_m", orNull(m.min_person_m)},
          {"min_body_gap_m", m.min_person_m < 0 ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(m.min_gap_m)},
          {"intimate_zone_s", m.intimate_s},
          {"personal_zone_s", m.personal_s},
          {"time_to_goal_s", orNull(m.time_to_goal_s)},
          {"path_length_m", m.path_length_m},
          {"time_lost_s", m.time_to_goal_s < 0 ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(m.time_lost_s)},
          {"max_jerk_m_s3", m.max_jerk_m_s3},
          {"mode_switches", m.mode_switches},
          {"pattern_switches", m.pattern_switches},
          {"pattern_accuracy", orNull(m.pattern_accuracy)},
          {"dominant_pattern", m.dominant_pattern},
          {"first_detection_s", orNull(m.detect_s)},
          {"enter_avoidance_s", orNull(m.enter_avoidance_s)},
          {"stop_s", orNull(m.stop_s)},
          {"slowest_s", orNull(m.slowest_s)},
          {"slowest_m_s", orNull(m.slowest_m_s)},
          {"min_speed_factor", m.min_speed_factor},
          {"false_tracks", m.false_tracks},
          {"person_in_cone_s", m.visible_s},
          {"missed_detection_s", m.missed_s},
          {"duration_s", m.duration_s}};
}

void progress(std::size_t done, std::size_t total, const std::string& what, bool tty) {
  const int width = 30;
  const int filled = total ? static_cast<int>(width * done / total) : width;
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar.resize(width, '.');
  if (tty)
    std::fprintf(stderr, "\r[%s] %zu/%zu %-40.40s", bar.c_str(), done, total, what.c_str());
  else if (done < total)
    std::fprintf(stderr, "[%zu/%zu] %s\n", done + 1, total, what.c_str());
  if (tty && done == total) std::fputc('\n', stderr);
  std::fflush(stderr);
}

void printTable(const sim::ScenarioSpec& s, const std::vector<sim::ScenarioRun>& runs) {
  std::printf("\n== %s: %s, world %s%s\n", s.name.c_str(), s.task.describe().c_str(), s.world.name.c_str(),
              s.expect_pattern != behavior::Pattern::kNone
                  ? (", expected pattern " + std::string(behavior::toString(s.expect_pattern))).c_str()
                  : "");
  std::vector<const sim::ScenarioRun*> cols;
  for (const auto& r : runs)
    if (r.people) cols.push_back(&r);
  std::printf("%-28s", "metric");
  for (const auto* r : cols) std::printf(" %16s", behavior::toString(r->policy));
  std::printf("\n");
  auto row = [&](const char* name, auto get) {
    std::printf("%-28s", name);
    for (const auto* r : cols) std::printf(" %16s", get(r->metrics).c_str());
    std::printf("\n");
  };
  using M = sim::RunMetrics;
  row("success", [](const M& m) { return std::string(m.success ? "yes" : "NO"); });
  row("collisions (people/walls)", [](const M& m) {
    return std::to_string(m.person_collisions) + "/" + std::to_string(m.wall_collisions);
  });
  row("min person distance (m)", [](const M& m) { return fmt(m.min_person_m); });
  row("min body gap (m)", [](const M& m) { return m.min_person_m < 0 ? std::string("-") : fmtSigned(m.min_gap_m); });
  row("intimate zone < 0.45 m (s)", [](const M& m) { return fmt(m.intimate_s); });
  row("personal zone < 1.2 m (s)", [](const M& m) { return fmt(m.personal_s); });
  row("time to goal (s)", [](const M& m) { return fmt(m.time_to_goal_s); });
  row("path length (m)", [](const M& m) { return fmt(m.path_length_m); });
  row("time lost vs no people (s)",
      [](const M& m) { return m.time_to_goal_s < 0 ? std::string("-") : fmtSigned(m.time_lost_s); });
  row("max jerk after 3 s (m/s^3)", [](const M& m) { return fmt(m.max_jerk_m_s3); });
  row("mode switches", [](const M& m) { return std::to_string(m.mode_switches); });
  row("pattern switches", [](const M& m) { return std::to_string(m.pattern_switches); });
  row("pattern accuracy", [](const M& m) { return m.pattern_accuracy < 0 ? std::string("-") : fmt(100 * m.pattern_accuracy, "%.0f %%"); });
  row("dominant pattern", [](const M& m) { return m.dominant_pattern; });
  row("first detection (s)", [](const M& m) { return fmt(m.detect_s); });
  row("person within max avoid (s)", [](const M& m) { return fmt(m.enter_avoidance_s); });
  row("stop (s)", [](const M& m) { return fmt(m.stop_s); });
  row("lowest speed (m/s) at (s)",
      [](const M& m) { return m.slowest_s < 0 ? std::string("-") : fmt(m.slowest_m_s) + " at " + fmt(m.slowest_s, "%.1f"); });
  row("min speed factor", [](const M& m) { return fmt(m.min_speed_factor); });
  row("false tracks", [](const M& m) { return std::to_string(m.false_tracks); });
  row("missed / in a cone (s)", [](const M& m) { return fmt(m.missed_s) + " / " + fmt(m.visible_s); });
  for (const auto* r : cols)
    if (!r->metrics.success)
      std::printf("  %s: %s\n", behavior::toString(r->policy), r->metrics.failure.c_str());
}

/// Each scenario once without people (the reference) and once per policy,
/// with a progress line; the runs per scenario, the reference last.
std::vector<std::vector<sim::ScenarioRun>> runSuite(const Options& o, const std::vector<sim::ScenarioSpec>& suite,
                                                    const sim::ScenarioContext& ctx, double& wall_s,
                                                    double& sim_seconds) {
  const bool tty = ::isatty(2);
  const std::size_t total = suite.size() * (o.policies.size() + 1);
  std::size_t done = 0;
  const auto wall0 = std::chrono::steady_clock::now();
  std::vector<std::vector<sim::ScenarioRun>> all;
  for (const auto& s : suite) {
    std::vector<sim::ScenarioRun> runs;
    progress(done, total, s.name + " without people", tty);
    CameraObserver ref_camera(s, ctx, o.camera, o.seed);
    sim::RunOptions ref_opt{behavior::SpeedPolicy::kFuzzy, false, o.seed, false, &ref_camera};
    const sim::ScenarioRun ref = sim::runScenario(s, ctx, ref_opt);
    sim_seconds += ref.metrics.duration_s;
    ++done;
    for (const auto p : o.policies) {
      progress(done, total, s.name + " " + behavior::toString(p), tty);
      CameraObserver camera(s, ctx, o.camera, o.seed);
      sim::ScenarioRun r = sim::runScenario(s, ctx, {p, true, o.seed, !o.plots.empty(), &camera});
      if (r.metrics.time_to_goal_s >= 0 && ref.metrics.time_to_goal_s >= 0)
        r.metrics.time_lost_s = r.metrics.time_to_goal_s - ref.metrics.time_to_goal_s;
      sim_seconds += r.metrics.duration_s;
      runs.push_back(std::move(r));
      ++done;
    }
    runs.push_back(ref);
    all.push_back(std::move(runs));
  }
  progress(done, total, "done", tty);
  std::fflush(stderr);
  wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return all;

}

/// The paper's timings next to ours (fuzzy strategy).
void printTimings(const std::vector<sim::ScenarioSpec>& suite, const std::vector<std::vector<sim::ScenarioRun>>& all) {
  std::printf("\n== timings vs the paper (fuzzy strategy; seconds from the start)\n");
  std::printf("%-16s %-30s %8s %8s\n", "scenario", "event", "ours", "paper");
  for (std::size_t i = 0; i < suite.size(); ++i) {
    const auto& s = suite[i];
    const sim::RunMetrics* m = nullptr;
    for (const auto& r : all[i])
      if (r.people && r.policy == behavior::SpeedPolicy::kFuzzy) m = &r.metrics;
    if (!m || (!s.paper.detect_s && !s.paper.enter_avoidance_s && !s.paper.stop_s && !s.paper.slowest_s)) continue;
    auto line = [&](const char* ev, double ours, const std::optional<double>& paper) {
      if (paper) std::printf("%-16s %-30s %8s %8.1f\n", s.name.c_str(), ev, fmt(ours).c_str(), *paper);
    };
    line("first detection", m->detect_s, s.paper.detect_s);
    line("enters max avoidance distance", m->enter_avoidance_s, s.paper.enter_avoidance_s);
    line("speed zero (< 0.02 m/s)", m->stop_s, s.paper.stop_s);
    line("lowest speed", m->slowest_s, s.paper.slowest_s);
  }

}

/// Successes and collisions per policy; whether every fuzzy-strategy run succeeded.
bool printSummary(const std::vector<sim::ScenarioSpec>& suite, const std::vector<std::vector<sim::ScenarioRun>>& all,
                  double wall_s, double sim_seconds) {
  int fuzzy_runs = 0, fuzzy_ok = 0;
  std::map<behavior::SpeedPolicy, std::pair<int, int>> per_policy;  // successes, collisions
  for (const auto& runs : all)
    for (const auto& r : runs) {
      if (!r.people) continue;
      auto& pp = per_policy[r.policy];
      pp.first += r.metrics.success ? 1 : 0;
      pp.second += static_cast<int>(r.metrics.person_collisions + r.metrics.wall_collisions);
      if (r.policy == behavior::SpeedPolicy::kFuzzy) {
        ++fuzzy_runs;
        fuzzy_ok += r.metrics.success ? 1 : 0;
      }
    }
  std::printf("\n== summary (%zu scenarios, %.0f s of sim time in %.1f s wall, %.0fx real time)\n", suite.size(),
              sim_seconds, wall_s, wall_s > 0 ? sim_seconds / wall_s : 0.0);
  for (const auto& [p, sc] : per_policy)
    std::printf("%-16s success %d/%zu, collisions %d\n", behavior::toString(p), sc.first, suite.size(), sc.second);

  return fuzzy_ok == fuzzy_runs;
}

void writePlots(const Options& o, const std::vector<sim::ScenarioSpec>& suite,
                const std::vector<std::vector<sim::ScenarioRun>>& all) {
  std::error_code ec;
  std::filesystem::create_directories(o.plots, ec);
  if (ec) std::fprintf(stderr, "scenario_suite: cannot create %s: %s\n", o.plots.c_str(), ec.message().c_str());
  for (std::size_t i = 0; i < suite.size(); ++i) {
    const std::string err = sim::plotScenario(o.plots, suite[i], all[i]);
    if (!err.empty()) std::fprintf(stderr, "scenario_suite: plot %s: %s\n", suite[i].name.c_str(), err.c_str());
  }
  std::printf("plots: %s/<scenario>.png\n", o.plots.c_str());
}

/// The figures as JSON (--json); false (printed why) when the file cannot be written.
bool writeJson(const Options& o, const std::vector<sim::ScenarioSpec>& suite,
               const std::vector<std::vector<sim::ScenarioRun>>& all, double wall_s, double sim_seconds) {
  nlohmann::ordered_json j;
  j["suite"] = o.suite;
  j["seed"] = o.seed;
  j["wall_s"] = wall_s;
  j["sim_s"] = sim_seconds;
  auto& js = j["scenarios"] = nlohmann::ordered_json::array();
  for (std::size_t i = 0; i < suite.size(); ++i) {
    const auto& s = suite[i];
    nlohmann::ordered_json e{{"name", s.name}, {"world", s.world.name}, {"task", s.task.describe()},
                             {"expect_pattern", std::string(behavior::toString(s.expect_pattern))}};
    e["paper"] = {{"detect_s", s.paper.detect_s ? nlohmann::ordered_json(*s.paper.detect_s) : nullptr},
                  {"enter_avoidance_s", s.paper.enter_avoidance_s ? nlohmann::ordered_json(*s.paper.enter_avoidance_s) : nullptr},
                  {"stop_s", s.paper.stop_s ? nlohmann::ordered_json(*s.paper.stop_s) : nullptr},
                  {"slowest_s", s.paper.slowest_s ? nlohmann::ordered_json(*s.paper.slowest_s) : nullptr}};
    for (const auto& r : all[i])
      e["runs"][r.people ? behavior::toString(r.policy) : "reference_no_people"] = toJson(r.metrics);
    js.push_back(std::move(e));
  }
  std::ofstream f(o.json);
  f << j.dump(2) << "\n";
  if (!f) {
    std::fprintf(stderr, "scenario_suite: cannot write %s\n", o.json.c_str());
    return false;
  }
  std::printf("json: %s\n", o.json.c_str());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  std::vector<sim::ScenarioSpec> suite;
  sim::ScenarioContext ctx;
  try {
    suite = sim::loadSuiteFile(o.suite);
    if (!o.only.empty()) {
      std::vector<sim::ScenarioSpec> picked;
      for (const auto& n : o.only) {
        bool found = false;
        for (const auto& s : suite)
          if (s.name == n) {
            picked.push_back(s);
            found = true;
          }
        if (!found) usageError("--only: no scenario '" + n + "' in " + o.suite);
      }
      suite = std::move(picked);
    }
    ctx = sim::loadScenarioContext(o.robot, o.control, o.behavior);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scenario_suite: %s\n", e.what());
    return 2;
  }

  double wall_s = 0, sim_seconds = 0;
  const auto all = runSuite(o, suite, ctx, wall_s, sim_seconds);
  for (std::size_t i = 0; i < suite.size(); ++i) printTable(suite[i], all[i]);
  printTimings(suite, all);
  const bool fuzzy_all_ok = printSummary(suite, all, wall_s, sim_seconds);
  if (!o.plots.empty()) writePlots(o, suite, all);
  if (!o.json.empty() && !writeJson(o, suite, all, wall_s, sim_seconds)) return 2;
  return fuzzy_all_ok ? 0 : 1;
}
