// Engine semantics against hand-computed MATLAB evalfis results, the
// no-rule and non-finite cases, and the no-allocation guarantee.
#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/alloc_counter.hpp"
#include "shared/fuzzy/engine.hpp"
#include "shared/fuzzy/fis_error.hpp"
#include "shared/fuzzy/fis_reader.hpp"
#include "shared/fuzzy/lookup_surface.hpp"
#include "tests/support/paths.hpp"

namespace inspect::fuzzy {
namespace {


// One input x on [0 1] with lo/hi triangles; one output y with lo/hi
// triangles; rules lo -> lo, hi -> hi. `system` replaces the method lines.
std::string oneInput(const std::string& type, const std::string& methods, const std::string& out_range,
                     const std::string& out_mfs, const std::string& rules) {
  return "[System]\nName='one'\nType='" + type + "'\nVersion=2.0\nNumInputs=1\nNumOutputs=1\nNumRules=" +
         std::to_string(std::count(rules.begin(), rules.end(), '\n')) + "\n" + methods +
         "\n[Input1]\nName='x'\nRange=[0 1]\nNumMFs=2\nMF1='lo':'trimf',[-1 0 1]\nMF2='hi':'trimf',[0 1 2]\n"
         "\n[Output1]\nName='y'\nRange=" + out_range + "\n" + out_mfs + "\n[Rules]\n" + rules;
}

std::string methods(const std::string& defuzz, const std::string& and_m = "min", const std::string& or_m = "max",
                    const std::string& imp = "min", const std::string& agg = "max") {
  return "AndMethod='" + and_m + "'\nOrMethod='" + or_m + "'\nImpMethod='" + imp + "'\nAggMethod='" + agg +
         "'\nDefuzzMethod='" + defuzz + "'\n";
}

const std::string kTriOut = "NumMFs=2\nMF1='lo':'trimf',[-1 0 1]\nMF2='hi':'trimf',[0 1 2]\n";
const std::string kLoLoHiHi = "1, 1 (1) : 1\n2, 2 (1) : 1\n";

double eval1(const std::string& text, double x, EvalStatus* status = nullptr, EngineOptions opt = {}) {
  Engine e(parseFis(text, "t.fis"), opt);
  double in[1] = {x};
  double out[1] = {0};
  const EvalStatus s = e.evaluate(in, out);
  if (status) *status = s;
  return out[0];
}

TEST(EngineMamdani, CentroidUsesMatlabs101Samples) {
  // x = 1: only 'hi' fires (1.0); the set is mu(y) = y on [0 1]. Over the 101
  // samples y_k = k/100 the centroid is sum k^2 / (100 sum k) = 0.67 exactly
  // (the continuous centroid would be 2/3).
  const std::string t = oneInput("mamdani", methods("centroid"), "[0 1]", kTriOut, kLoLoHiHi);
  EXPECT_NEAR(eval1(t, 1.0), 0.67, 1e-12);
  // Symmetric firing gives the middle.
  EXPECT_NEAR(eval1(t, 0.5), 0.5, 1e-12);
  // More samples approach the continuous value.
  EngineOptions fine;
  fine.num_samples = 100001;
  EXPECT_NEAR(eval1(t, 1.0, nullptr, fine), 2.0 / 3.0, 1e-5);
}

TEST(EngineMamdani, BisectorIsFirstSampleReachingHalfTheArea) {
  // Same set mu = k/100: running sum k(k+1)/2 first reaches 2525 at k = 71.
  const std::string t = oneInput("mamdani", methods("bisector"), "[0 1]", kTriOut, kLoLoHiHi);
  EXPECT_NEAR(eval1(t, 1.0), 0.71, 1e-12);
}

TEST(EngineMamdani, MaximumBasedDefuzzifiers) {
  // x = 0.7: lo fires 0.3, hi fires 0.7; the clipped set peaks (0.7) on
  // y in [0.70, 1.00]: samples 70..100.
  EXPECT_NEAR(eval1(oneInput("mamdani", methods("mom"), "[0 1]", kTriOut, kLoLoHiHi), 0.7), 0.85, 1e-12);
  EXPECT_NEAR(eval1(oneInput("mamdani", methods("som"), "[0 1]", kTriOut, kLoLoHiHi), 0.7), 0.70, 1e-12);
  EXPECT_NEAR(eval1(oneInput("mamdani", methods("lom"), "[0 1]", kTriOut, kLoLoHiHi), 0.7), 1.00, 1e-12);
}

TEST(EngineMamdani, MomAveragesEveryMaximumEvenAcrossGaps) {
  // Two rules fire equally (x = 0.5) on disjoint output terms: MATLAB's mom
  // averages both plateaus (fuzzylite's MeanOfMaximum takes the first only).
  // The plateaus (>= 0.5) are [0, 0.2525] and [0.7475, 1]: samples 0..25 and 75..100.
  const std::string outs = "NumMFs=2\nMF1='lo':'trapmf',[0 0 0.2 0.305]\nMF2='hi':'trapmf',[0.695 0.8 1 1]\n";
  EXPECT_NEAR(eval1(oneInput("mamdani", methods("mom"), "[0 1]", outs, kLoLoHiHi), 0.5), 0.5, 1e-12);
}

TEST(EngineMamdani, SomAndLomCompareAbsoluteValues) {
  // Plateau on y in [-1.5, -0.5]: MATLAB's som is the smallest |y| (-0.5),
  // lom the largest |y| (-1.5).
  const std::string outs = "NumMFs=1\nMF1='p':'trapmf',[-2 -1.5 -0.5 0]\n";
  const std::string rules = "2, 1 (1) : 1\n";
  EXPECT_NEAR(eval1(oneInput("mamdani", methods("som"), "[-2 0]", outs, rules), 1.0), -0.5, 1e-12);
  EXPECT_NEAR(eval1(oneInput("mamdani", methods("lom"), "[-2 0]", outs, rules), 1.0), -1.5, 1e-12);
  // Across zero: smallest |y| is 0 itself.
  const std::string across = "NumMFs=1\nMF1='p':'trapmf',[-2 -1 1 2]\n";
  EXPECT_NEAR(eval1(oneInput("mamdani", methods("som"), "[-2 2]", across, rules), 1.0), 0.0, 1e-12);
}

TEST(EngineMamdani, NegatedConsequentComplementsTheOutputMf) {
  // MATLAB: a negative consequent index implies 1 - mu(y). x = 1 fires 'hi'
  // fully; NOT hi on [0 1] is 1 - y, whose centroid over y_k = k/100 is
  // (50.5 - 33.835) / (101 - 50.5) = 0.33. (fuzzylite instead negates the
  // firing strength, 1 - 1 = 0, and fires nothing.)
  const std::string t = oneInput("mamdani", methods("centroid"), "[0 1]", kTriOut, "2, -2 (1) : 1\n");
  EXPECT_NEAR(eval1(t, 1.0), 0.33, 1e-12);
}

TEST(EngineMamdani, ProductImplicationAndSumAggregation) {
  // x = 0.7, prod implication: 0.3 * lo(y) + 0.7 * hi(y) = 0.3 + 0.4 y on [0 1].
  // Centroid over y_k = k/100: sum (0.3 + 0.4 y) y / sum (0.3 + 0.4 y).
  double num = 0, den = 0;
  for (int k = 0; k <= 100; ++k) {
    const double y = k / 100.0;
    num += (0.3 + 0.4 * y) * y;
    den += 0.3 + 0.4 * y;
  }
  const std::string t = oneInput("mamdani", methods("centroid", "min", "max", "prod", "sum"), "[0 1]", kTriOut, kLoLoHiHi);
  EXPECT_NEAR(eval1(t, 0.7), num / den, 1e-12);
  // probor aggregation: a + b - ab of the clipped sets.
  num = den = 0;
  for (int k = 0; k <= 100; ++k) {
    const double y = k / 100.0;
    const double a = std::min(0.3, 1 - y), b = std::min(0.7, y);
    const double m = a + b - a * b;
    num += m * y;
    den += m;
  }
  const std::string p = oneInput("mamdani", methods("centroid", "min", "max", "min", "probor"), "[0 1]", kTriOut, kLoLoHiHi);
  EXPECT_NEAR(eval1(p, 0.7), num / den, 1e-12);
}

// Two inputs a, b on [0 1] (lo/hi triangles), Sugeno output with constants
// 0 and 10: the output is the firing strength of the 'hi' rule when the two
// strengths add to one, which makes the connectives easy to check by hand.
std::string twoInputSugeno(const std::string& and_m, const std::string& or_m, const std::string& defuzz,
                           const std::string& rules) {
  return "[System]\nName='two'\nType='sugeno'\nVersion=2.0\nNumInputs=2\nNumOutputs=1\nNumRules=" +
         std::to_string(std::count(rules.begin(), rules.end(), '\n')) + "\n" +
         methods(defuzz, and_m, or_m, "prod", "sum") +
         "\n[Input1]\nName='a'\nRange=[0 1]\nNumMFs=2\nMF1='lo':'trimf',[-1 0 1]\nMF2='hi':'trimf',[0 1 2]\n"
         "\n[Input2]\nName='b'\nRange=[0 1]\nNumMFs=2\nMF1='lo':'trimf',[-1 0 1]\nMF2='hi':'trimf',[0 1 2]\n"
         "\n[Output1]\nName='z'\nRange=[0 10]\nNumMFs=3\nMF1='zero':'constant',[0]\nMF2='ten':'constant',[10]\n"
         "MF3='lin':'linear',[3 -2 1]\n\n[Rules]\n" + rules;
}

double eval2(const std::string& text, double a, double b, EvalStatus* status = nullptr) {
  Engine e(parseFis(text, "t.fis"));
  double in[2] = {a, b};
  double out[1] = {0};
  const EvalStatus s = e.evaluate(in, out);
  if (status) *status = s;
  return out[0];
}

TEST(EngineSugeno, WeightedSumOfConnectives) {
  // a = 0.6 (hi 0.6, lo 0.4), b = 0.3 (hi 0.3, lo 0.7). wtsum of one rule with
  // constant 10 gives 10 x its firing strength.
  const double a = 0.6, b = 0.3;
  struct Case {
    const char* and_m;
    const char* or_m;
    const char* rule;
    double strength;
  };
  for (const Case& c : {Case{"min", "max", "2 2, 2 (1) : 1\n", 0.3}, Case{"prod", "max", "2 2, 2 (1) : 1\n", 0.18},
                        Case{"min", "max", "2 2, 2 (1) : 2\n", 0.6}, Case{"min", "probor", "2 2, 2 (1) : 2\n", 0.72},
                        Case{"min", "max", "-2 2, 2 (1) : 1\n", 0.3},   // NOT hi(a) = 0.4, min with 0.3
                        Case{"min", "max", "-2 -2, 2 (1) : 1\n", 0.4},  // min(0.4, 0.7)
                        Case{"min", "max", "0 2, 2 (1) : 1\n", 0.3},    // don't care on a
                        Case{"min", "max", "0 2, 2 (1) : 2\n", 0.3},    // don't care in OR
                        Case{"min", "max", "2 2, 2 (0.5) : 1\n", 0.15}}) {
    SCOPED_TRACE(std::string(c.and_m) + " " + c.or_m + " " + c.rule);
    EXPECT_NEAR(eval2(twoInputSugeno(c.and_m, c.or_m, "wtsum", c.rule), a, b), 10 * c.strength, 1e-12);
  }
}

TEST(EngineSugeno, WeightedAverageWithConstantAndLinearOutputs) {
  // lo-lo -> 0 (w 0.4*0.7 = 0.28 by prod), hi-hi -> 10 (0.18, weight 0.5 -> 0.09),
  // hi-lo -> linear 3a - 2b + 1 = 2.2 (0.6*0.7 = 0.42).
  const std::string rules = "1 1, 1 (1) : 1\n2 2, 2 (0.5) : 1\n2 1, 3 (1) : 1\n";
  const double w1 = 0.28, w2 = 0.09, w3 = 0.42;
  const double z = (w1 * 0 + w2 * 10 + w3 * 2.2) / (w1 + w2 + w3);
  EXPECT_NEAR(eval2(twoInputSugeno("prod", "max", "wtaver", rules), 0.6, 0.3), z, 1e-12);
  EXPECT_NEAR(eval2(twoInputSugeno("prod", "max", "wtsum", rules), 0.6, 0.3), w2 * 10 + w3 * 2.2, 1e-12);
}

TEST(EngineNoRule, MamdaniAndSugenoGiveTheMiddleOfTheRange) {
  // Input terms leave a gap on (0.4, 0.6): at x = 0.5 no rule fires.
  const std::string gap = "NumMFs=2\nMF1='lo':'trimf',[0 0 0.4]\nMF2='hi':'trimf',[0.6 1 1]\n";
  auto withGap = [&](std::string t) {
    const std::string from = "NumMFs=2\nMF1='lo':'trimf',[-1 0 1]\nMF2='hi':'trimf',[0 1 2]\n";
    t.replace(t.find(from), from.size(), gap);
    return t;
  };
  EvalStatus s = EvalStatus::kOk;
  const std::string outs = "NumMFs=2\nMF1='lo':'trimf',[0 2 4]\nMF2='hi':'trimf',[6 8 10]\n";
  for (const char* d : {"centroid", "bisector", "mom", "som", "lom"}) {
    EXPECT_DOUBLE_EQ(eval1(withGap(oneInput("mamdani", methods(d), "[0 10]", outs, kLoLoHiHi)), 0.5, &s), 5.0) << d;
    EXPECT_EQ(s, EvalStatus::kNoRuleFired);
  }
  const std::string souts = "NumMFs=2\nMF1='lo':'constant',[1]\nMF2='hi':'constant',[2]\n";
  for (const char* d : {"wtaver", "wtsum"}) {
    const std::string t = withGap(oneInput("sugeno", methods(d, "min", "max", "prod", "sum"), "[-4 10]", souts, kLoLoHiHi));
    EXPECT_DOUBLE_EQ(eval1(t, 0.5, &s), 3.0) << d;
    EXPECT_EQ(s, EvalStatus::kNoRuleFired);
    EXPECT_DOUBLE_EQ(eval1(t, 0.0, &s), 1.0) << d;
    EXPECT_EQ(s, EvalStatus::kOk);
  }
}

TEST(EngineNoRule, EmptyOutputSetGivesTheMiddleOfTheRange) {
  // The rule fires but its output MF is zero on every sample of [0 10].
  const std::string outs = "NumMFs=2\nMF1='lo':'trimf',[11 12 13]\nMF2='hi':'trimf',[6 8 10]\n";
  EvalStatus s = EvalStatus::kNoRuleFired;
  EXPECT_DOUBLE_EQ(eval1(oneInput("mamdani", methods("centroid"), "[0 10]", outs, kLoLoHiHi), 0.0, &s), 5.0);
  EXPECT_EQ(s, EvalStatus::kOk);
}

TEST(EngineGuards, NonFiniteInputGivesNaNAndStatus) {
  Engine e(readFisFile(inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis")));
  std::array<double, 3> out{};
  for (double bad : {std::nan(""), HUGE_VAL, -HUGE_VAL}) {
    const std::array<double, 2> in{0.5, bad};
    EXPECT_EQ(e.evaluate(in, out), EvalStatus::kNonFiniteInput);
    for (double o : out) EXPECT_TRUE(std::isnan(o));
  }
  const std::array<double, 1> short_in{0.5};
  EXPECT_EQ(e.evaluate(short_in, out), EvalStatus::kBadSize);
  const std::array<double, 2> in{0.5, 0.5};
  EXPECT_EQ(e.evaluate(in, out), EvalStatus::kOk);
  for (double o : out) EXPECT_TRUE(std::isfinite(o));
}

TEST(EngineGuards, OutOfRangeInputsAreNotClippedUnlessAsked) {
  // x = 1.5 is outside [0 1]: hi = trimf [0 1 2] gives 0.5 as MATLAB and
  // fuzzylite evaluate it; clipped to 1 it gives 1.0.
  const std::string t = oneInput("sugeno", methods("wtsum", "min", "max", "prod", "sum"), "[0 10]",
                                 "NumMFs=2\nMF1='lo':'constant',[0]\nMF2='hi':'constant',[10]\n", kLoLoHiHi);
  EXPECT_NEAR(eval1(t, 1.5), 5.0, 1e-12);
  EngineOptions clip;
  clip.clip_inputs = true;
  EXPECT_NEAR(eval1(t, 1.5, nullptr, clip), 10.0, 1e-12);
}

TEST(EngineGuards, RefusesIncompleteSystemsAndBadOptions) {
  Fis f = readFisFile(inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis"));
  EngineOptions bad;
  bad.num_samples = 1;
  EXPECT_THROW(Engine(f, bad), FisError);
  f.rules[3].consequent[1] = 8;
  EXPECT_THROW(Engine{f}, FisError);
}

// The rule tables as the cited source prints them (rows e = NB..PB, columns
// ec = NB..PB); the shipped file must hold exactly these.
constexpr const char* kKpTable[7] = {"PB PB PM PM PS ZO ZO", "PB PB PM PS PS ZO NS", "PM PM PM PS ZO NS NS",
                                     "PM PM PS ZO NS NM NM", "PS PS ZO NS NS NM NM", "PS ZO NS NM NM NM NB",
                                     "ZO ZO NM NM NM NB NB"};
constexpr const char* kKiTable[7] = {"NB NB NM NM NS ZO ZO", "NB NB NM NS NS ZO ZO", "NB NM NS NS ZO PS PS",
                                     "NM NM NS ZO PS PM PM", "NM NS ZO PS PS PM PB", "ZO ZO PS PS PM PB PB",
                                     "ZO ZO PS PM PM PB PB"};
constexpr const char* kKdTable[7] = {"PS NS NB NB NB NM PS", "PS NS NB NM NM NS ZO", "ZO NS NM NM NS NS ZO",
                                     "ZO NS NS NS NS NS ZO", "ZO ZO ZO ZO ZO ZO ZO", "PB NS PS PS PS PS PB",
                                     "PB PM PM PM PS PS PB"};

int termIndex(const std::string& t) {
  const char* names[7] = {"NB", "NM", "NS", "ZO", "PS", "PM", "PB"};
  for (int i = 0; i < 7; ++i) {
    if (t == names[i]) return i + 1;
  }
  return 0;
}

TEST(ShippedFuzzyPid, RulesAreTheCitedTables) {
  const Fis f = readFisFile(inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis"));
  ASSERT_EQ(f.rules.size(), 49u);
  const char* const* tables[3] = {kKpTable, kKiTable, kKdTable};
  for (const Rule& r : f.rules) {
    const int i = r.antecedent[0] - 1, j = r.antecedent[1] - 1;
    for (int o = 0; o < 3; ++o) {
      std::istringstream row(tables[o][i]);
      std::string cell;
      for (int k = 0; k <= j; ++k) row >> cell;
      EXPECT_EQ(r.consequent[static_cast<std::size_t>(o)], termIndex(cell)) << "output " << o << " e " << i << " ec " << j;
    }
    EXPECT_EQ(r.weight, 1.0);
    EXPECT_EQ(r.connection, Connection::kAnd);
  }
}

TEST(ShippedFuzzyPid, SurfaceFollowsTheTables) {
  // At the centre of each (e, ec) cell its own rule fires fully and the
  // neighbours at 0.0625: the correction has the sign of the table entry.
  Engine e(readFisFile(inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis")));
  const char* const* tables[3] = {kKpTable, kKiTable, kKdTable};
  std::array<double, 3> out{};
  for (int i = 0; i < 7; ++i) {
    for (int j = 0; j < 7; ++j) {
      const std::array<double, 2> in{i - 3.0, j - 3.0};
      ASSERT_EQ(e.evaluate(in, out), EvalStatus::kOk);
      for (int o = 0; o < 3; ++o) {
        std::istringstream row(tables[o][i]);
        std::string cell;
        for (int k = 0; k <= j; ++k) row >> cell;
        const int t = termIndex(cell) - 4;  // -3 .. 3
        if (t > 0) {
          EXPECT_GT(out[static_cast<std::size_t>(o)], 0.3) << o << " " << i << " " << j;
        } else if (t < 0) {
          EXPECT_LT(out[static_cast<std::size_t>(o)], -0.3) << o << " " << i << " " << j;
        } else {
          EXPECT_NEAR(out[static_cast<std::size_t>(o)], 0.0, 0.6) << o << " " << i << " " << j;
        }
      }
    }
  }
  const std::array<double, 2> zero{0, 0};
  ASSERT_EQ(e.evaluate(zero, out), EvalStatus::kOk);
  EXPECT_NEAR(out[1], 0.0, 1e-9);  // ki ZO, and its neighbours balance
  EXPECT_LT(out[2], -0.5);         // kd NS
}

TEST(EngineAllocation, EvaluateNeverAllocates) {
  std::vector<Engine> engines;
  engines.emplace_back(readFisFile(inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis")));
  for (const char* f : {"shapes_bisector", "shapes_sum_centroid", "shapes_probor_centroid", "peak_mom", "peak_som",
                        "sugeno_wtaver", "sugeno_wtsum"}) {
    engines.emplace_back(readFisFile(inspect::test::srcPath("tests/shared/fuzzy/data/") + f + ".fis"));
  }
  const LookupSurface surface(readFisFile(inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis")));
  std::array<double, 3> out{};
  double sink = 0;
  const std::size_t before = inspect::test::allocationCount();
  for (auto& e : engines) {
    for (int i = 0; i < 200; ++i) {
      const std::array<double, 2> in{-3.5 + 0.037 * i, 7.0 - 0.071 * i};
      e.evaluate(in, std::span<double>(out.data(), e.numOutputs()));
      sink += out[0];
    }
    const std::array<double, 2> nan_in{std::nan(""), 0};
    e.evaluate(nan_in, std::span<double>(out.data(), e.numOutputs()));
  }
  for (int i = 0; i < 200; ++i) {
    const std::array<double, 2> in{-3.5 + 0.037 * i, 3.0 - 0.031 * i};
    surface.evaluate(in, out);
    sink += out[0];
  }
  const std::size_t after = inspect::test::allocationCount();
  EXPECT_EQ(after - before, 0u) << "evaluate() allocated";
  EXPECT_TRUE(std::isfinite(sink));
  // The counter does see allocations (a test that cannot fail is a bug).
  const std::size_t c0 = inspect::test::allocationCount();
  auto* v = new std::vector<double>(100);
  delete v;
  EXPECT_GT(inspect::test::allocationCount(), c0);
}

}  // namespace
}  // namespace inspect::fuzzy
