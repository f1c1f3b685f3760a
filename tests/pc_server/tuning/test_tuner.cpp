// The fuzzy-PID tuner (pc_server/tuning/tuner.hpp): the cost, robust
// evaluations over scenarios, the optimiser against the real closed loop,
// cancellation and the refusal of bad set-ups.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "pc_server/tuning/tuner.hpp"
#include "shared/config/control_config.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/fuzzy/fis_reader.hpp"
#include "sim/robot_plant.hpp"
#include "tests/support/paths.hpp"
#include "tests/pc_server/tuning/paper_gains.hpp"

using namespace inspect;
using namespace inspect::tuning;

namespace {

/// The repository's configs, the nominal plant, the paper's circle; small scenario counts.
TuneSetup baseSetup() {
  TuneSetup s;
  s.robot = config::loadRobotConfigFile(inspect::test::srcPath("config/robot.yaml"));
  s.control = config::loadControlConfigFile(inspect::test::srcPath("config/control.yaml"));
  config::applyRobot(s.control, s.robot);
  s.fis = fuzzy::readFisFile(s.control.fis_path);
  s.plant = sim::nominalPlant(s.robot);
  s.plant_variations = 2;
  s.seeds = 1;
  s.threads = 2;
  return s;
}

using inspect::test::paperGains;

/// A worn robot: weaker, slower, delayed and unequal wheels.
control::PlantModel wornPlant(control::PlantModel p) {
  p.left.gain = 0.85;
  p.right.gain = 0.95;
  p.left.time_constant_s = 0.32;
  p.right.time_constant_s = 0.28;
  p.left.dead_time_s = p.right.dead_time_s = 0.04;
  return p;
}

sim::ClosedLoopMetrics typicalRun() {
  sim::ClosedLoopMetrics m;
  m.max_pos_err_m = 0.08;
  m.max_ang_err_rad = 0.09;
  m.rms_pos_err_m = 0.02;
  m.rms_ang_err_rad = 0.01;
  m.converge_pos_s = 18.0;
  m.converge_ang_s = 20.0;
  m.effort = 600.0;
  m.command_variation = 40.0;
  m.saturated_s = 0.5;
  m.duration_s = 44.0;
  m.final_pos_err_m = 0.002;
  return m;
}

constexpr double kRefEffort = 550.0;

struct MetricCase {
  const char* name;
  double sim::ClosedLoopMetrics::*field;
  double step;
};

// Test names, not bytes, in gtest's and ctest's listings.
void PrintTo(const MetricCase& c, std::ostream* os) { *os << c.name; }

class CostIsMonotone : public ::testing::TestWithParam<MetricCase> {};

TEST_P(CostIsMonotone, GrowsWithEachTerm) {
  const CostWeights w;
  const auto c = GetParam();
  sim::ClosedLoopMetrics m = typicalRun();
  double prev = costOf(m, w, kRefEffort);
  for (int i = 0; i < 8; ++i) {
    m.*c.field += c.step;
    const double now = costOf(m, w, kRefEffort);
    EXPECT_GT(now, prev) << c.name << " step " << i;
    EXPECT_TRUE(std::isfinite(now));
    prev = now;
  }
}

INSTANTIATE_TEST_SUITE_P(Terms, CostIsMonotone,
                         ::testing::Values(MetricCase{"max_pos", &sim::ClosedLoopMetrics::max_pos_err_m, 0.02},
                                           MetricCase{"rms_pos", &sim::ClosedLoopMetrics::rms_pos_err_m, 0.005},
                                           MetricCase{"max_ang", &sim::ClosedLoopMetrics::max_ang_err_rad, 0.05},
                                           MetricCase{"rms_ang", &sim::ClosedLoopMetrics::rms_ang_err_rad, 0.01},
                                           MetricCase{"converge_pos", &sim::ClosedLoopMetrics::converge_pos_s, 3.0},
                                           MetricCase{"converge_ang", &sim::ClosedLoopMetrics::converge_ang_s, 2.9},
                                           MetricCase{"effort", &sim::ClosedLoopMetrics::effort, 20.0},
                                           MetricCase{"saturation", &sim::ClosedLoopMetrics::saturated_s, 1.0}),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(Cost, NotConvergedAndDivergedRunsCostMuchButStayFinite) {
  const CostWeights w;
  const auto good = typicalRun();
  const double base = costOf(good, w, kRefEffort);
  EXPECT_GT(base, 0.0);
  EXPECT_LT(base, 50.0);

  auto still_outside = good;
  still_outside.converge_pos_s = still_outside.duration_s;  // outside the band at the end
  EXPECT_GE(costOf(still_outside, w, kRefEffort), base + 49.0);

  auto far = good;
  far.max_pos_err_m = 3.0;
  auto farther = far;
  farther.max_pos_err_m = 30.0;
  EXPECT_GE(costOf(far, w, kRefEffort), 1e4);
  EXPECT_GT(costOf(farther, w, kRefEffort), costOf(far, w, kRefEffort));

  const double inf = std::numeric_limits<double>::infinity();
  for (double bad : {std::nan(""), inf, -inf}) {
    for (auto field : {&sim::ClosedLoopMetrics::max_pos_err_m, &sim::ClosedLoopMetrics::rms_ang_err_rad,
                       &sim::ClosedLoopMetrics::effort, &sim::ClosedLoopMetrics::converge_ang_s}) {
      auto m = good;
      m.*field = bad;
      const double c = costOf(m, w, kRefEffort);
      EXPECT_TRUE(std::isfinite(c));
      EXPECT_GE(c, costOf(farther, w, kRefEffort));
    }
  }
  // No reference effort (a degenerate path): the effort term is left out, not divided by zero.
  EXPECT_TRUE(std::isfinite(costOf(good, w, 0.0)));
}

TEST(Cost, WeightsScaleTheirTerms) {
  auto m = typicalRun();
  CostWeights only_max_pos{1, 0, 0, 0, 0, 0, 0};
  EXPECT_NEAR(costOf(m, only_max_pos, kRefEffort), 0.08 / 0.05, 1e-12);
  CostWeights only_effort{0, 0, 0, 0, 0, 1, 0};
  EXPECT_NEAR(costOf(m, only_effort, kRefEffort), 600.0 / 550.0 - 1.0, 1e-12);
  m.effort = 500.0;  // less than the reference's own: no reward
  EXPECT_DOUBLE_EQ(costOf(m, only_effort, kRefEffort), 0.0);
}

TEST(TunerEvaluate, DeterministicAndIndependentOfThreadCount) {
  auto s = baseSetup();
  s.plant_variations = 3;
  s.seeds = 2;
  s.threads = 1;
  const Tuner one(s);
  s.threads = 2;
  const Tuner two(s);
  const auto g = paperGains(s);
  const Evaluation a = one.evaluate(g), b = one.evaluate(g), c = two.evaluate(g);
  EXPECT_EQ(a.scenarios, 6);
  EXPECT_EQ(c.scenarios, 6);
  EXPECT_TRUE(std::isfinite(a.cost));
  EXPECT_EQ(a.cost, b.cost);
  EXPECT_EQ(a.cost, c.cost);
  EXPECT_EQ(a.mean.rms_pos_err_m, c.mean.rms_pos_err_m);
  EXPECT_EQ(a.worst.max_ang_err_rad, c.worst.max_ang_err_rad);
  EXPECT_EQ(a.nominal.effort, c.nominal.effort);
  // Worst is a bound on mean and on the nominal run.
  EXPECT_GE(a.worst.max_pos_err_m, a.mean.max_pos_err_m);
  EXPECT_GE(a.worst.max_pos_err_m, a.nominal.max_pos_err_m);
  // The nominal run is the trace's run (plant itself, first seed) without samples.
  const auto t = one.trace(g, control::WheelControl::kFuzzyPid, s.seed);
  EXPECT_EQ(t.metrics.max_pos_err_m, a.nominal.max_pos_err_m);
  EXPECT_FALSE(t.samples.empty());
}

TEST(TunerEvaluate, PidUsesTheBaseGainsOnly) {
  auto s = baseSetup();
  s.plant_variations = 1;
  const Tuner t(s);
  auto g = paperGains(s);
  const Evaluation pid = t.evaluate(g, control::WheelControl::kPid);
  const Evaluation fuzzy = t.evaluate(g, control::WheelControl::kFuzzyPid);
  EXPECT_NE(pid.cost, fuzzy.cost);
  g.fuzzy.k1 = 7.0;  // a fuzzy scaling: the PID does not see it, the fuzzy-PID does
  EXPECT_EQ(t.evaluate(g, control::WheelControl::kPid).cost, pid.cost);
  EXPECT_NE(t.evaluate(g, control::WheelControl::kFuzzyPid).cost, fuzzy.cost);
  g.fuzzy.base.kp = 4.0;
  EXPECT_NE(t.evaluate(g, control::WheelControl::kPid).cost, pid.cost);
}

TEST(TunerEvaluate, PlantVariationsAreHarderThanThePlantAlone) {
  auto s = baseSetup();
  s.plant_variations = 1;
  const auto g = paperGains(s);
  const Evaluation alone = Tuner(s).evaluate(g);
  s.plant_variations = 4;
  s.dead_spread_s = 0.05;
  const Evaluation varied = Tuner(s).evaluate(g);
  EXPECT_EQ(varied.scenarios, 4);
  EXPECT_EQ(varied.nominal.max_pos_err_m, alone.nominal.max_pos_err_m);  // variation 0 is the plant itself
  EXPECT_GT(varied.worst.max_pos_err_m, alone.worst.max_pos_err_m);
  EXPECT_GT(varied.cost, alone.cost);
}

TEST(TunerRun, ImprovesThePaperGainsOnAWornPlant) {
  auto s = baseSetup();
  s.plant = wornPlant(s.plant);
  s.max_evals = 120;
  const auto start = paperGains(s);
  Tuner t(s);
  int calls = 0;
  double last_best = std::numeric_limits<double>::infinity();
  bool monotone = true;
  const auto r = t.run(start, [&](const TuneProgress& p) {
    ++calls;
    monotone = monotone && p.best_cost <= last_best;
    last_best = p.best_cost;
    EXPECT_EQ(p.evals, calls);
    EXPECT_EQ(p.max_evals, 120);
  }, nullptr);
  EXPECT_FALSE(r.cancelled);
  EXPECT_LE(r.evals, 120);
  EXPECT_GE(r.evals, 100);  // the budget is used, not abandoned early
  EXPECT_EQ(calls, r.evals);
  EXPECT_TRUE(monotone);
  EXPECT_EQ(static_cast<int>(r.best_cost_history.size()), r.evals);
  EXPECT_EQ(r.best_cost_history.back(), r.best_eval.cost);
  EXPECT_EQ(r.best_cost_history.front(), r.initial_eval.cost);
  EXPECT_LE(r.best_eval.cost, 0.9 * r.initial_eval.cost)
      << "initial " << r.initial_eval.cost << " best " << r.best_eval.cost << " (" << r.algorithm << ")";
  EXPECT_EQ(control::validateGains(r.best), "");
  // The untuned gains are the start's; the reported cost is the best gains' own.
  EXPECT_EQ(r.best.aux.a1, start.aux.a1);
  EXPECT_EQ(t.evaluate(r.best).cost, r.best_eval.cost);
  EXPECT_FALSE(r.algorithm.empty());
}

TEST(TunerRun, NeverWorseThanTheStartAndWithinTheBudget) {
  auto s = baseSetup();
  s.plant_variations = 1;
  s.max_evals = 12;
  s.params = {"kp", "ki"};
  s.bounds["kp"] = {20.0, 30.0};  // the start (9) lies outside: the search box cannot beat it on every point
  Tuner t(s);
  const auto start = paperGains(s);
  const auto r = t.run(start, {}, nullptr);
  EXPECT_LE(r.evals, 12);
  EXPECT_LE(r.best_eval.cost, r.initial_eval.cost);
  if (r.best_eval.cost == r.initial_eval.cost) {
    EXPECT_TRUE(control::sameGains(r.best, start));
  }
}

TEST(TunerRun, CancelStopsWithinOneEvaluationKeepingTheBest) {
  auto s = baseSetup();
  s.plant_variations = 1;
  s.max_evals = 200;
  Tuner t(s);
  std::atomic<bool> cancel{false};
  int calls = 0;
  const auto r = t.run(paperGains(s), [&](const TuneProgress& p) {
    ++calls;
    if (p.evals == 15) cancel = true;
  }, &cancel);
  EXPECT_TRUE(r.cancelled);
  EXPECT_EQ(r.evals, 15);
  EXPECT_EQ(calls, 15);
  EXPECT_LE(r.best_eval.cost, r.initial_eval.cost);
  EXPECT_EQ(r.best_cost_history.size(), 15u);
  EXPECT_EQ(r.best_cost_history.back(), r.best_eval.cost);
}

struct BadSetup {
  const char* name;
  std::function<void(TuneSetup&)> spoil;
  const char* message;  // a part of what()
};

void PrintTo(const BadSetup& b, std::ostream* os) { *os << b.name; }

class TunerRefuses : public ::testing::TestWithParam<BadSetup> {};

TEST_P(TunerRefuses, NamingTheProblem) {
  auto s = baseSetup();
  GetParam().spoil(s);
  try {
    Tuner t(s);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(GetParam().message), std::string::npos) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Setups, TunerRefuses,
    ::testing::Values(
        BadSetup{"UnknownParam", [](TuneSetup& s) { s.params = {"kp", "kq"}; }, "unknown parameter 'kq'"},
        BadSetup{"EmptyParams", [](TuneSetup& s) { s.params.clear(); }, "params is empty"},
        BadSetup{"DuplicateParam", [](TuneSetup& s) { s.params = {"kp", "kp"}; }, "'kp' is listed twice"},
        BadSetup{"LoNotBelowHi", [](TuneSetup& s) { s.bounds["ki"] = {3.0, 3.0}; }, "bounds of ki [3, 3]"},
        BadSetup{"OutsideGainBounds", [](TuneSetup& s) { s.bounds["a1"] = {-30.0, -1.0}; },
                 "outside the allowed range [-20, 0]"},
        BadSetup{"BoundsOfUnknownGain", [](TuneSetup& s) { s.bounds["zz"] = {0.0, 1.0}; }, "unknown parameter 'zz'"},
        BadSetup{"BadPlant", [](TuneSetup& s) { s.plant.right.time_constant_s = 0.0; },
                 "plant: right.time_constant_s"},
        BadSetup{"NoVariations", [](TuneSetup& s) { s.plant_variations = 0; }, "plant_variations = 0"},
        BadSetup{"NoSeeds", [](TuneSetup& s) { s.seeds = 0; }, "seeds = 0"},
        BadSetup{"TooFewEvals", [](TuneSetup& s) { s.max_evals = 9; }, "max_evals = 9"},
        BadSetup{"NegativeThreads", [](TuneSetup& s) { s.threads = -1; }, "threads = -1"},
        BadSetup{"NegativeWeight", [](TuneSetup& s) { s.weights.effort = -1; }, "weight effort"},
        BadSetup{"GlobalFraction", [](TuneSetup& s) { s.global_fraction = 1.5; }, "global_fraction"},
        BadSetup{"UnknownAlgorithm", [](TuneSetup& s) { s.global_algorithm = "GN_MAGIC"; }, "GN_MAGIC"},
        BadSetup{"FisNotFuzzyPidShaped", [](TuneSetup& s) { s.fis.outputs.pop_back(); }, "fis: "}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(TunerRun, RefusesInvalidStartGains) {
  auto s = baseSetup();
  Tuner t(s);
  auto g = paperGains(s);
  g.aux.a2 = 1.0;
  EXPECT_THROW(t.run(g, {}, nullptr), std::invalid_argument);
}

}  // namespace
