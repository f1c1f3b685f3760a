// The fuzzy speed strategy (paper Table 1, Eq 9): config/fuzzy/speed_strategy.fis
// and its wrapper SpeedStrategy. Dense-grid property tests (stop inside the
// sensitive distance, speed never rising as the distance shrinks), the rule
// table (paper's 8 rules verbatim, 32-combination completion as documented in
// docs/speed-strategy.md) and agreement with the fuzzylite command-line tool.
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "shared/behavior/speed_strategy.hpp"
#include "shared/config/config_node.hpp"
#include "shared/fuzzy/engine.hpp"
#include "shared/fuzzy/fis_error.hpp"
#include "shared/fuzzy/fis_reader.hpp"
#include "shared/fuzzy/fis_writer.hpp"
#include "tests/support/paths.hpp"

namespace inspect::behavior {
namespace {

namespace fs = std::filesystem;

const std::string kFisPath = inspect::test::srcPath("config/fuzzy/speed_strategy.fis");
constexpr std::array<Pattern, 4> kPatterns{Pattern::kCrossing, Pattern::kEncountering, Pattern::kLeading,
                                           Pattern::kConfronting};
constexpr double kSlack = 1e-9;  // numerical slack of the monotonicity checks

const fuzzy::Fis& shippedFis() {
  static const fuzzy::Fis fis = fuzzy::readFisFile(kFisPath);
  return fis;
}

// dV of the raw system at (distance fraction, speed, pattern).
double rawDv(fuzzy::Engine& engine, double x, double v, double pattern) {
  const std::array<double, 3> in{x, v, pattern};
  std::array<double, 1> out{};
  EXPECT_EQ(engine.evaluate(in, out), fuzzy::EvalStatus::kOk) << "x " << x << " v " << v << " pattern " << pattern;
  return out[0];
}

// Grid 0, step, 2 step, ... up to and including `last` (within rounding).
std::vector<double> axis(double last, double step) {
  std::vector<double> xs;
  const int n = static_cast<int>(std::lround(last / step));
  for (int i = 0; i <= n; ++i) xs.push_back(last * i / n);
  return xs;
}

const std::vector<double>& speeds() {
  static const std::vector<double> v = axis(2.5, 0.05);  // 51 human speeds, m/s
  return v;
}

int mfIndex(const fuzzy::Variable& v, const std::string& name) {
  for (std::size_t i = 0; i < v.mfs.size(); ++i)
    if (v.mfs[i].name == name) return static_cast<int>(i) + 1;
  ADD_FAILURE() << v.name << " has no term " << name;
  return -100;
}

struct TableRow {
  const char* d;
  const char* v;
  const char* b;
  const char* out;
};

// Paper Table 1, rows 1-8, in the paper's order.
constexpr std::array<TableRow, 8> kPaperRules{{
    {"DS", "VS", "BS", "VD"},
    {"DS", "VF", "BS", "VD"},
    {"DE", "VS", "BE", "VI"},
    {"DE", "VF", "BE", "VZ"},
    {"DN", "VS", "BL", "VR"},
    {"DN", "VF", "BL", "VI"},
    {"DF", "VS", "BF", "VT"},
    {"DF", "VF", "BF", "VT"},
}};

// Rules 9-32: the completion documented in docs/speed-strategy.md, file order.
constexpr std::array<TableRow, 24> kCompletion{{
    {"DS", "VS", "BE", "VD"}, {"DS", "VF", "BE", "VD"}, {"DS", "VS", "BL", "VD"}, {"DS", "VF", "BL", "VD"},
    {"DS", "VS", "BF", "VD"}, {"DS", "VF", "BF", "VD"}, {"DE", "VS", "BS", "VZ"}, {"DE", "VF", "BS", "VZ"},
    {"DE", "VS", "BL", "VI"}, {"DE", "VF", "BL", "VZ"}, {"DE", "VS", "BF", "VZ"}, {"DE", "VF", "BF", "VD"},
    {"DN", "VS", "BS", "VI"}, {"DN", "VF", "BS", "VZ"}, {"DN", "VS", "BE", "VR"}, {"DN", "VF", "BE", "VI"},
    {"DN", "VS", "BF", "VI"}, {"DN", "VF", "BF", "VZ"}, {"DF", "VS", "BS", "VT"}, {"DF", "VF", "BS", "VT"},
    {"DF", "VS", "BE", "VT"}, {"DF", "VF", "BE", "VT"}, {"DF", "VS", "BL", "VT"}, {"DF", "VF", "BL", "VT"},
}};

void expectRule(const fuzzy::Fis& fis, std::size_t r, const TableRow& row) {
  ASSERT_LT(r, fis.rules.size());
  const fuzzy::Rule& rule = fis.rules[r];
  const std::vector<int> ante{mfIndex(fis.inputs[0], row.d), mfIndex(fis.inputs[1], row.v),
                              mfIndex(fis.inputs[2], row.b)};
  EXPECT_EQ(rule.antecedent, ante) << "rule " << r + 1 << " should read " << row.d << " " << row.v << " " << row.b;
  EXPECT_EQ(rule.consequent, std::vector<int>{mfIndex(fis.outputs[0], row.out)}) << "rule " << r + 1;
  EXPECT_EQ(rule.weight, 1.0) << "rule " << r + 1;
  EXPECT_EQ(rule.connection, fuzzy::Connection::kAnd) << "rule " << r + 1;
}

// --- The .fis file -------------------------------------------------------

TEST(SpeedStrategyFis, HasTheDocumentedTermsAndOutputs) {
  const fuzzy::Fis& fis = shippedFis();
  ASSERT_EQ(fis.type, fuzzy::FisType::kSugeno);
  EXPECT_EQ(fis.defuzz_method, fuzzy::DefuzzMethod::kWtaver);
  EXPECT_EQ(fis.and_method, fuzzy::AndMethod::kProd);
  ASSERT_EQ(fis.inputs.size(), 3u);
  ASSERT_EQ(fis.outputs.size(), 1u);
  const std::array<std::vector<std::string>, 3> names{
      {{"DS", "DE", "DN", "DF"}, {"VS", "VF"}, {"BS", "BE", "BL", "BF"}}};
  for (std::size_t i = 0; i < 3; ++i) {
    ASSERT_EQ(fis.inputs[i].mfs.size(), names[i].size());
    for (std::size_t t = 0; t < names[i].size(); ++t) EXPECT_EQ(fis.inputs[i].mfs[t].name, names[i][t]);
  }
  // Output constants: VD = 1 (stop), VZ = 0.75, VI = 0.5, VR = 0.25, VT = 0 (speed kept).
  const std::array<std::pair<const char*, double>, 5> out{{{"VD", 1.0}, {"VZ", 0.75}, {"VI", 0.5}, {"VR", 0.25}, {"VT", 0.0}}};
  ASSERT_EQ(fis.outputs[0].mfs.size(), out.size());
  for (std::size_t t = 0; t < out.size(); ++t) {
    EXPECT_EQ(fis.outputs[0].mfs[t].name, out[t].first);
    EXPECT_EQ(fis.outputs[0].mfs[t].type, fuzzy::MfType::kConstant);
    EXPECT_EQ(fis.outputs[0].mfs[t].params, std::vector<double>{out[t].second});
  }
  // Distance terms peak at DS edge 0.4 (1.2 m of 3 m), 0.75, 0.9, 1.0 of the avoidance distance.
  const std::array<double, 4> peaks{0.4, 0.75, 0.9, 1.0};
  for (std::size_t t = 0; t < 4; ++t) {
    const auto& mf = fis.inputs[0].mfs[t];
    EXPECT_EQ(fuzzy::mfValue(mf.type, mf.params, peaks[t]), 1.0) << mf.name;
  }
  // VS and VF cross at the average walking speed, 1.3 m/s.
  for (const auto& mf : fis.inputs[1].mfs) EXPECT_DOUBLE_EQ(fuzzy::mfValue(mf.type, mf.params, 1.3), 0.5) << mf.name;
}

// The file survives our writer unchanged (comments and all), as the shipped
// fuzzy_pid.fis does.
TEST(SpeedStrategyFis, RoundTripsThroughTheWriter) {
  const fuzzy::Fis& fis = shippedFis();
  EXPECT_FALSE(fis.comments.empty());
  EXPECT_EQ(fuzzy::parseFis(fuzzy::formatFis(fis), "speed_strategy.fis"), fis);
}

// (d) The paper's eight rules, verbatim and first.
TEST(SpeedStrategyFis, StartsWithThePaperRulesVerbatim) {
  const fuzzy::Fis& fis = shippedFis();
  for (std::size_t r = 0; r < kPaperRules.size(); ++r) expectRule(fis, r, kPaperRules[r]);
}

// The completion is the documented table, and each of the 4 x 2 x 4 term
// combinations has exactly one rule.
TEST(SpeedStrategyFis, CompletionIsTheDocumentedTableWithOneRulePerCombination) {
  const fuzzy::Fis& fis = shippedFis();
  ASSERT_EQ(fis.rules.size(), 32u);
  for (std::size_t r = 0; r < kCompletion.size(); ++r) expectRule(fis, r + 8, kCompletion[r]);
  std::array<int, 32> count{};
  for (const auto& rule : fis.rules) {
    ASSERT_EQ(rule.antecedent.size(), 3u);
    for (int a : rule.antecedent) ASSERT_GT(a, 0) << "every rule names all three inputs";
    ++count[static_cast<std::size_t>((rule.antecedent[0] - 1) * 8 + (rule.antecedent[1] - 1) * 4 +
                                     (rule.antecedent[2] - 1))];
  }
  for (std::size_t c = 0; c < count.size(); ++c) EXPECT_EQ(count[c], 1) << "combination " << c;
  // Every DS rule stops, every DF rule keeps the speed.
  for (const auto& rule : fis.rules) {
    if (rule.antecedent[0] == 1) {
      EXPECT_EQ(rule.consequent[0], mfIndex(fis.outputs[0], "VD"));
    }
    if (rule.antecedent[0] == 4) {
      EXPECT_EQ(rule.consequent[0], mfIndex(fis.outputs[0], "VT"));
    }
  }
}

// (c) At its terms' centres, each of the 32 combinations fires its own rule,
// and that rule dominates.
TEST(SpeedStrategyFis, EveryCombinationFiresAtItsTermCentres) {
  const fuzzy::Fis& fis = shippedFis();
  fuzzy::Engine engine(fis);
  const std::array<double, 4> d_centre{0.4, 0.75, 0.9, 1.0};  // DS: its full-membership edge
  const std::array<double, 2> v_centre{0.0, 2.5};             // sigmoids: the range end where each is largest
  for (int d = 1; d <= 4; ++d) {
    for (int v = 1; v <= 2; ++v) {
      for (int b = 1; b <= 4; ++b) {
        const std::array<double, 3> in{d_centre[d - 1], v_centre[v - 1], static_cast<double>(b)};
        std::array<double, 1> out{};
        ASSERT_EQ(engine.evaluate(in, out), fuzzy::EvalStatus::kOk) << d << " " << v << " " << b;
        const auto w = engine.firingStrengths();
        const auto strongest = static_cast<std::size_t>(std::max_element(w.begin(), w.end()) - w.begin());
        EXPECT_EQ(fis.rules[strongest].antecedent, (std::vector<int>{d, v, b}));
        EXPECT_GT(w[strongest], 0.99);
        // At the centre the output is (almost) that rule's constant.
        const double z = fis.outputs[0].mfs[static_cast<std::size_t>(fis.rules[strongest].consequent[0] - 1)].params[0];
        EXPECT_NEAR(out[0], z, 0.01) << d << " " << v << " " << b;
      }
    }
  }
}

// (a) on the raw system: for every distance fraction at or inside the
// sensitive edge 0.4, every pattern and speed, dV is exactly 1.
TEST(SpeedStrategyFis, StopsExactlyInsideTheSensitiveDistance) {
  fuzzy::Engine engine(shippedFis());
  std::size_t n = 0;
  for (int b = 1; b <= 4; ++b) {
    for (double v : speeds()) {
      for (double x : axis(0.4, 0.0005)) {
        const double dv = rawDv(engine, x, v, b);
        ASSERT_EQ(dv, 1.0) << "x " << x << " v " << v << " pattern " << b;
        ++n;
      }
    }
  }
  EXPECT_EQ(n, 4u * 51u * 801u);
  // Just outside, the robot creeps again (the stop is not wider than DS).
  for (int b = 1; b <= 4; ++b) EXPECT_LT(rawDv(engine, 0.41, 0.0, b), 1.0);
}

// (b) on the raw system: for fixed pattern and speed, dV never decreases as
// the distance fraction shrinks (speed factor non-decreasing in distance);
// also never decreases as the person gets faster, and the patterns keep
// their order of caution: confronting >= crossing >= encountering >= leading.
TEST(SpeedStrategyFis, MonotoneInDistanceAndSpeedAndOrderedByPattern) {
  fuzzy::Engine engine(shippedFis());
  const std::vector<double> xs = axis(1.2, 0.0005);  // 2401 fractions
  const std::vector<double>& vs = speeds();
  // dv[b][v][x]
  std::vector<std::vector<std::vector<double>>> dv(4, std::vector<std::vector<double>>(vs.size()));
  for (int b = 1; b <= 4; ++b)
    for (std::size_t j = 0; j < vs.size(); ++j)
      for (double x : xs) dv[b - 1][j].push_back(rawDv(engine, x, vs[j], b));

  double worst_d = 0.0, worst_v = 0.0, worst_b = 0.0;
  for (std::size_t b = 0; b < 4; ++b) {
    for (std::size_t j = 0; j < vs.size(); ++j) {
      for (std::size_t i = 1; i < xs.size(); ++i) {
        const double rise = dv[b][j][i] - dv[b][j][i - 1];  // > 0: slower when farther
        worst_d = std::max(worst_d, rise);
        ASSERT_LE(rise, kSlack) << "pattern " << b + 1 << " v " << vs[j] << " x " << xs[i];
        if (j > 0) {
          const double drop = dv[b][j - 1][i] - dv[b][j][i];  // > 0: faster person, faster robot
          worst_v = std::max(worst_v, drop);
          ASSERT_LE(drop, kSlack) << "pattern " << b + 1 << " v " << vs[j] << " x " << xs[i];
        }
      }
    }
  }
  // Caution order (pattern index 0 = BS, 1 = BE, 2 = BL, 3 = BF): BF >= BS >= BE >= BL.
  for (std::size_t j = 0; j < vs.size(); ++j) {
    for (std::size_t i = 0; i < xs.size(); ++i) {
      const double bf = dv[3][j][i], bs = dv[0][j][i], be = dv[1][j][i], bl = dv[2][j][i];
      worst_b = std::max({worst_b, bs - bf, be - bs, bl - be});
      ASSERT_GE(bf + kSlack, bs) << "v " << vs[j] << " x " << xs[i];
      ASSERT_GE(bs + kSlack, be) << "v " << vs[j] << " x " << xs[i];
      ASSERT_GE(be + kSlack, bl) << "v " << vs[j] << " x " << xs[i];
    }
  }
  std::printf("SPEED monotonicity: worst violation distance %.3g, speed %.3g, pattern order %.3g\n", worst_d, worst_v,
              worst_b);
}

// --- The wrapper ---------------------------------------------------------

// (a) and (b) through SpeedStrategy in metres, over 0 .. 1.2 max_avoidance_m,
// with the default sensitive distance and with a smaller one (where the
// file's own DS zone, not the wrapper's floor, must give the stop).
TEST(SpeedStrategy, DenseGridStopsInsideSensitiveAndNeverSpeedsUpWhenCloser) {
  for (double sensitive_m : {1.2, 0.9}) {
    SCOPED_TRACE("sensitive_m " + std::to_string(sensitive_m));
    const SpeedStrategyParams params{3.0, sensitive_m};
    SpeedStrategy s(shippedFis(), params);
    const std::vector<double> ds = axis(1.2 * params.max_avoidance_m, 0.001);  // 3601 distances
    for (Pattern p : kPatterns) {
      for (double v : speeds()) {
        double prev = -1.0;
        for (double d : ds) {
          const double f = s.speedFactor(d, v, p);
          ASSERT_GE(f, 0.0);
          ASSERT_LE(f, 1.0);
          EXPECT_NEAR(s.lastDv(), 1.0 - f, 1e-15);
          if (d <= 1.2) {
            ASSERT_EQ(f, 0.0) << toString(p) << " d " << d << " v " << v;  // the file's stop zone
          }
          if (d >= params.max_avoidance_m) {
            ASSERT_EQ(f, 1.0) << toString(p) << " d " << d;
          }
          ASSERT_GE(f, prev - kSlack) << toString(p) << " d " << d << " v " << v;
          prev = f;
        }
      }
    }
  }
}

// (e) Beyond the maximum avoidance distance the speed is kept, and the factor
// reaches 1 continuously (every DF rule is VT).
TEST(SpeedStrategy, KeepsSpeedAtAndBeyondTheMaximumAvoidanceDistance) {
  SpeedStrategy s(shippedFis(), {});
  for (Pattern p : kPatterns) {
    for (double v : {0.0, 0.5, 1.3, 2.5, 4.0}) {
      for (double d : {3.0, 3.0001, 3.3, 3.6, 10.0, 1e9}) EXPECT_EQ(s.speedFactor(d, v, p), 1.0) << d;
      EXPECT_GT(s.speedFactor(3.0 * (1 - 1e-6), v, p), 0.999);
      EXPECT_LT(s.speedFactor(2.7, v, p), 1.0) << "DN slows every pattern";
    }
  }
}

TEST(SpeedStrategy, PaperRulesAtTheirTermCentres) {
  SpeedStrategy s(shippedFis(), {});
  // DE (2.25 m), encountering: slow -> VI (half speed), fast -> VZ (quarter speed).
  EXPECT_NEAR(s.speedFactor(2.25, 0.0, Pattern::kEncountering), 0.5, 0.002);
  EXPECT_NEAR(s.speedFactor(2.25, 2.5, Pattern::kEncountering), 0.25, 0.002);
  // DN (2.7 m), leading: slow -> VR (75 %), fast -> VI (50 %).
  EXPECT_NEAR(s.speedFactor(2.7, 0.0, Pattern::kLeading), 0.75, 0.002);
  EXPECT_NEAR(s.speedFactor(2.7, 2.5, Pattern::kLeading), 0.5, 0.002);
}

TEST(SpeedStrategy, NoneKeepsSpeedAndBadInputsStop) {
  SpeedStrategy s(shippedFis(), {});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(s.speedFactor(0.5, 1.0, Pattern::kNone), 1.0);
  EXPECT_EQ(s.speedFactor(nan, nan, Pattern::kNone), 1.0);
  EXPECT_EQ(s.lastDv(), 0.0);
  for (Pattern p : kPatterns) {
    EXPECT_EQ(s.speedFactor(nan, 1.0, p), 0.0);
    EXPECT_EQ(s.lastDv(), 1.0);
    EXPECT_EQ(s.speedFactor(inf, 1.0, p), 0.0);
    EXPECT_EQ(s.speedFactor(2.5, nan, p), 0.0);
    EXPECT_EQ(s.speedFactor(2.5, -inf, p), 0.0);
    EXPECT_EQ(s.speedFactor(-1.0, 1.0, p), 0.0);
    // The speed is a magnitude.
    EXPECT_EQ(s.speedFactor(2.5, -1.7, p), s.speedFactor(2.5, 1.7, p));
  }
  EXPECT_EQ(s.speedFactor(2.5, 1.0, static_cast<Pattern>(7)), 0.0);
}

TEST(SpeedStrategy, RejectsBadParameters) {
  const fuzzy::Fis& fis = shippedFis();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const SpeedStrategyParams& p : {SpeedStrategyParams{0.0, 1.2}, SpeedStrategyParams{3.0, 0.0},
                                       SpeedStrategyParams{3.0, 3.0}, SpeedStrategyParams{nan, 1.2},
                                       SpeedStrategyParams{3.0, nan}, SpeedStrategyParams{-3.0, -1.0}}) {
    EXPECT_THROW(SpeedStrategy(fis, p), config::ConfigError) << p.max_avoidance_m << " " << p.sensitive_m;
  }
  // 1.5 m of 3 m lies where DE already fires: the file would not stop there.
  try {
    SpeedStrategy(fis, {3.0, 1.5});
    FAIL() << "sensitive_m beyond the file's stop zone was accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("stop zone"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(SpeedStrategy(fis, {2.5, 1.0}));  // 0.4 of 2.5 m: the edge itself
}

TEST(SpeedStrategy, RejectsSystemsOfTheWrongShape) {
  const fuzzy::Fis& good = shippedFis();
  auto expectFisError = [](const fuzzy::Fis& fis, const std::string& needle) {
    try {
      SpeedStrategy(fis, {});
      ADD_FAILURE() << "accepted; expected an error containing '" << needle << "'";
    } catch (const fuzzy::FisError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  expectFisError(fuzzy::readFisFile(inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis")), "Sugeno");
  fuzzy::Fis missing = good;
  missing.rules.erase(missing.rules.begin() + 20);  // rule 21: DN VS BS
  expectFisError(missing, "no rule for DN and VS and BS");
  fuzzy::Fis wide = good;
  wide.inputs[2].mfs[0].params = {0.0, 1.0, 2.1};  // BS still fires at pattern 2
  expectFisError(wide, "pattern term 'BS'");
  fuzzy::Fis big = good;
  big.outputs[0].mfs[0].params = {1.5};
  expectFisError(big, "constant in [0, 1]");
  fuzzy::Fis slow_ds = good;
  slow_ds.rules[0].consequent = {2};  // DS VS BS -> VZ: no longer a stop
  EXPECT_THROW(SpeedStrategy(slow_ds, {}), config::ConfigError);
}

TEST(SpeedStrategy, LoaderNamesTheFile) {
  EXPECT_NO_THROW(loadSpeedStrategy(kFisPath));
  try {
    loadSpeedStrategy("/nonexistent/speed.fis");
    FAIL();
  } catch (const fuzzy::FisError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/speed.fis"), std::string::npos) << e.what();
  }
  const std::string pid = inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis");
  try {
    loadSpeedStrategy(pid);
    FAIL();
  } catch (const fuzzy::FisError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(pid + ": ", 0), 0u) << e.what();
  }
}

// --- (f) Agreement with fuzzylite ---------------------------------------

std::string readAll(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Same approach as tests/shared/fuzzy/test_fuzzylite_reference.cpp: the Debian
// `fuzzylite` tool evaluates the file on a grid; Sugeno, so no sampling
// difference: 1e-9. fuzzylite skips rules firing below its macheps (1e-6),
// MATLAB (and we) do not; on such rows ours is recomputed without them.
TEST(SpeedStrategyFis, AgreesWithFuzzylite) {
  ASSERT_EQ(std::system("command -v fuzzylite >/dev/null 2>&1"), 0)
      << "the fuzzylite command-line tool is not installed (Debian package 'fuzzylite'; scripts/setup.sh installs it)";
  const fuzzy::Fis& fis = shippedFis();
  // Regular and irrationally shifted axes; patterns at the integers and in between.
  std::vector<double> xs = axis(1.2, 0.02), vs = axis(2.5, 0.25);
  for (int i = 0; i < 23; ++i) xs.push_back(1.2 * (i + 0.381966011250105) / 23.0);
  for (int i = 0; i < 7; ++i) vs.push_back(2.5 * (i + 0.381966011250105) / 7.0);
  const std::vector<double> bs{1, 2, 3, 4, 0.7, 1.3, 2.2, 2.8, 3.6, 4.3};
  std::vector<std::array<double, 3>> rows;
  for (double b : bs)
    for (double v : vs)
      for (double x : xs) rows.push_back({x, v, b});

  const fs::path dir = fs::temp_directory_path() / ("inspect_speed_strategy_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  {
    std::ofstream in(dir / "inputs.fld");
    char buf[96];
    for (const auto& r : rows) {
      std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g\n", r[0], r[1], r[2]);
      in << buf;
    }
  }
  const std::string cmd = "fuzzylite -i '" + kFisPath + "' -if fis -of fld -d '" + (dir / "inputs.fld").string() +
                          "' -o '" + (dir / "outputs.fld").string() +
                          "' -decimals 12 -dheader false -dinputs true >/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::vector<double> ref;
  {
    std::istringstream is(readAll(dir / "outputs.fld"));
    std::string line;
    while (std::getline(is, line)) {
      std::istringstream ls(line);
      std::string tok, last;
      int cols = 0;
      while (ls >> tok) {
        last = tok;
        ++cols;
      }
      if (cols == 0) continue;
      ASSERT_EQ(cols, 4) << line;
      double v = std::nan("");
      auto [p, ec] = std::from_chars(last.data(), last.data() + last.size(), v);
      ASSERT_TRUE(ec == std::errc() && p == last.data() + last.size()) << "fuzzylite printed '" << last << "'";
      ref.push_back(v);
    }
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
  ASSERT_EQ(ref.size(), rows.size());

  fuzzy::Engine engine(fis);
  double max_diff = 0.0, raw_max = 0.0;
  std::size_t weak_rows = 0, failures = 0;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    std::array<double, 1> out{};
    ASSERT_EQ(engine.evaluate(rows[r], out), fuzzy::EvalStatus::kOk);
    ASSERT_FALSE(std::isnan(ref[r])) << "fuzzylite fired no rule at row " << r;
    double ours = out[0];
    raw_max = std::max(raw_max, std::abs(ours - ref[r]));
    fuzzy::Fis weak = fis;
    bool any = false;
    const auto w = engine.firingStrengths();
    for (std::size_t k = 0; k < w.size(); ++k) {
      if (w[k] > 0.0 && w[k] < 1e-6) {
        weak.rules[k].weight = 0.0;
        any = true;
      }
    }
    if (any) {
      ++weak_rows;
      fuzzy::Engine(weak).evaluate(rows[r], out);
      ours = out[0];
    }
    const double d = std::abs(ours - ref[r]);
    max_diff = std::max(max_diff, d);
    if (d > 1e-9 && ++failures <= 5)
      ADD_FAILURE() << "at (" << rows[r][0] << ", " << rows[r][1] << ", " << rows[r][2] << "): ours " << ours
                    << ", fuzzylite " << ref[r];
  }
  std::printf("SPEED fuzzylite rows %zu weak %zu max|diff| %.3g (raw %.3g) tol 1e-9\n", rows.size(), weak_rows,
              max_diff, raw_max);
}

}  // namespace
}  // namespace inspect::behavior
