// Each membership function against values computed by hand from MATLAB's
// definitions, and the parameter checks.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "shared/fuzzy/membership_function.hpp"

namespace inspect::fuzzy {
namespace {

struct MfCase {
  const char* label;
  MfType type;
  std::vector<double> params;
  double x;
  double expected;
};

void PrintTo(const MfCase& c, std::ostream* os) { *os << c.label << " at x=" << c.x; }

class MfValueTest : public ::testing::TestWithParam<MfCase> {};

TEST_P(MfValueTest, MatchesHandComputedValue) {
  const MfCase& c = GetParam();
  EXPECT_NEAR(mfValue(c.type, c.params, c.x), c.expected, 1e-9) << c.label << " x=" << c.x;
}

const double kE05 = std::exp(-0.5);  // gaussian one sigma away

INSTANTIATE_TEST_SUITE_P(
    Matlab, MfValueTest,
    ::testing::Values(
        MfCase{"trimf", MfType::kTrimf, {0, 2.5, 5}, -1, 0}, MfCase{"trimf", MfType::kTrimf, {0, 2.5, 5}, 0, 0},
        MfCase{"trimf", MfType::kTrimf, {0, 2.5, 5}, 1.25, 0.5}, MfCase{"trimf", MfType::kTrimf, {0, 2.5, 5}, 2.5, 1},
        MfCase{"trimf", MfType::kTrimf, {0, 2.5, 5}, 3.75, 0.5}, MfCase{"trimf", MfType::kTrimf, {0, 2.5, 5}, 5, 0},
        MfCase{"trimf", MfType::kTrimf, {0, 2.5, 5}, 6, 0},
        // Vertical left side: the peak wins at x == a == b (MATLAB trimf.m).
        MfCase{"trimf a=b", MfType::kTrimf, {0, 0, 4}, 0, 1}, MfCase{"trimf a=b", MfType::kTrimf, {0, 0, 4}, 2, 0.5},
        MfCase{"trimf a=b", MfType::kTrimf, {0, 0, 4}, -0.1, 0},
        MfCase{"trimf b=c", MfType::kTrimf, {0, 4, 4}, 4, 1}, MfCase{"trimf b=c", MfType::kTrimf, {0, 4, 4}, 4.1, 0},
        MfCase{"trimf a=b=c", MfType::kTrimf, {1, 1, 1}, 1, 1},
        MfCase{"trimf a=b=c", MfType::kTrimf, {1, 1, 1}, 1.1, 0},
        MfCase{"trapmf", MfType::kTrapmf, {2, 4, 6, 8}, 1, 0}, MfCase{"trapmf", MfType::kTrapmf, {2, 4, 6, 8}, 3, 0.5},
        MfCase{"trapmf", MfType::kTrapmf, {2, 4, 6, 8}, 4, 1}, MfCase{"trapmf", MfType::kTrapmf, {2, 4, 6, 8}, 5, 1},
        MfCase{"trapmf", MfType::kTrapmf, {2, 4, 6, 8}, 7.5, 0.25},
        MfCase{"trapmf", MfType::kTrapmf, {2, 4, 6, 8}, 8, 0},
        MfCase{"trapmf vertical", MfType::kTrapmf, {2, 2, 6, 6}, 2, 1},
        MfCase{"trapmf vertical", MfType::kTrapmf, {2, 2, 6, 6}, 6, 1},
        MfCase{"trapmf vertical", MfType::kTrapmf, {2, 2, 6, 6}, 1.99, 0},
        MfCase{"trapmf vertical", MfType::kTrapmf, {2, 2, 6, 6}, 6.01, 0},
        MfCase{"gaussmf", MfType::kGaussmf, {2, 1}, 1, 1}, MfCase{"gaussmf", MfType::kGaussmf, {2, 1}, 3, kE05},
        MfCase{"gaussmf", MfType::kGaussmf, {2, 1}, -1, kE05},
        MfCase{"gaussmf crossing", MfType::kGaussmf, {0.5 / std::sqrt(2 * std::log(2.0)), 0}, 0.5, 0.5},
        MfCase{"gauss2mf", MfType::kGauss2mf, {1, 0, 2, 4}, -1, kE05},
        MfCase{"gauss2mf", MfType::kGauss2mf, {1, 0, 2, 4}, 2, 1},
        MfCase{"gauss2mf", MfType::kGauss2mf, {1, 0, 2, 4}, 6, kE05},
        // c1 > c2: both sides act in the middle: exp(-1/8) * exp(-1/8).
        MfCase{"gauss2mf crossed", MfType::kGauss2mf, {1, 2, 1, 1}, 1.5, std::exp(-0.25)},
        MfCase{"gbellmf", MfType::kGbellmf, {2, 4, 6}, 6, 1}, MfCase{"gbellmf", MfType::kGbellmf, {2, 4, 6}, 8, 0.5},
        MfCase{"gbellmf", MfType::kGbellmf, {2, 4, 6}, 4, 0.5},
        MfCase{"gbellmf", MfType::kGbellmf, {2, 4, 6}, 10, 1.0 / 257.0},
        MfCase{"sigmf", MfType::kSigmf, {2, 4}, 4, 0.5},
        MfCase{"sigmf", MfType::kSigmf, {2, 4}, 5, 1.0 / (1.0 + std::exp(-2.0))},
        MfCase{"sigmf falling", MfType::kSigmf, {-2, 4}, 5, 1.0 / (1.0 + std::exp(2.0))},
        MfCase{"smf", MfType::kSmf, {1, 3}, 0, 0}, MfCase{"smf", MfType::kSmf, {1, 3}, 1.5, 0.125},
        MfCase{"smf", MfType::kSmf, {1, 3}, 2, 0.5}, MfCase{"smf", MfType::kSmf, {1, 3}, 2.5, 0.875},
        MfCase{"smf", MfType::kSmf, {1, 3}, 3, 1}, MfCase{"smf", MfType::kSmf, {1, 3}, 4, 1},
        MfCase{"zmf", MfType::kZmf, {1, 3}, 0, 1}, MfCase{"zmf", MfType::kZmf, {1, 3}, 1.5, 0.875},
        MfCase{"zmf", MfType::kZmf, {1, 3}, 2, 0.5}, MfCase{"zmf", MfType::kZmf, {1, 3}, 2.5, 0.125},
        MfCase{"zmf", MfType::kZmf, {1, 3}, 3, 0},
        MfCase{"pimf", MfType::kPimf, {0, 2, 4, 6}, 0.5, 0.125}, MfCase{"pimf", MfType::kPimf, {0, 2, 4, 6}, 1, 0.5},
        MfCase{"pimf", MfType::kPimf, {0, 2, 4, 6}, 3, 1}, MfCase{"pimf", MfType::kPimf, {0, 2, 4, 6}, 5, 0.5},
        MfCase{"pimf", MfType::kPimf, {0, 2, 4, 6}, 7, 0},
        // |sig(5,2) - sig(5,7)| at the midpoint 4.5 is tanh(6.25).
        MfCase{"dsigmf", MfType::kDsigmf, {5, 2, 5, 7}, 4.5, std::tanh(6.25)},
        MfCase{"dsigmf", MfType::kDsigmf, {5, 2, 5, 7}, 2, 0.5},
        MfCase{"dsigmf", MfType::kDsigmf, {5, 7, 5, 2}, 4.5, std::tanh(6.25)},  // absolute value
        MfCase{"psigmf", MfType::kPsigmf, {2, 3, -5, 8}, 3, 0.5},
        MfCase{"psigmf", MfType::kPsigmf, {2, 3, -5, 8}, 8, 0.5 / (1.0 + std::exp(-10.0))}));

TEST(SugenoOutput, ConstantAndLinear) {
  const std::vector<double> x{2.0, -1.0};
  EXPECT_DOUBLE_EQ(sugenoOutput(MfType::kConstant, std::vector<double>{7.5}, x), 7.5);
  EXPECT_DOUBLE_EQ(sugenoOutput(MfType::kLinear, std::vector<double>{0.5, 3.0, 1.0}, x), 0.5 * 2 - 3 + 1);
}

TEST(MfTypeName, RoundTripsEveryType) {
  for (MfType t : {MfType::kTrimf, MfType::kTrapmf, MfType::kGaussmf, MfType::kGauss2mf, MfType::kGbellmf,
                   MfType::kSigmf, MfType::kDsigmf, MfType::kPsigmf, MfType::kSmf, MfType::kZmf, MfType::kPimf,
                   MfType::kConstant, MfType::kLinear}) {
    auto back = parseMfType(mfTypeName(t));
    ASSERT_TRUE(back.has_value()) << mfTypeName(t);
    EXPECT_EQ(*back, t);
  }
  EXPECT_FALSE(parseMfType("trimff").has_value());
}

struct ParamCase {
  MfType type;
  std::vector<double> params;
  std::size_t num_inputs;
  const char* expected;  // substring of the problem; "" = fine
};

inline void PrintTo(const ParamCase& c, std::ostream* os) {
  *os << c.params.size() << " params, expect '" << c.expected << "'";
}

class MfParamTest : public ::testing::TestWithParam<ParamCase> {};

TEST_P(MfParamTest, ReportsProblem) {
  const ParamCase& c = GetParam();
  const std::string p = mfParamProblem(c.type, c.params, c.num_inputs);
  if (std::string(c.expected).empty()) {
    EXPECT_EQ(p, "");
  } else {
    EXPECT_NE(p.find(c.expected), std::string::npos) << "got: " << p;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Checks, MfParamTest,
    ::testing::Values(ParamCase{MfType::kTrimf, {0, 1, 2}, 1, ""},
                      ParamCase{MfType::kTrimf, {0, 1}, 1, "trimf needs 3 parameters, got 2"},
                      ParamCase{MfType::kTrimf, {2, 1, 0}, 1, "a <= b <= c"},
                      ParamCase{MfType::kTrapmf, {0, 3, 2, 4}, 1, "a <= b <= c <= d"},
                      ParamCase{MfType::kGaussmf, {0, 1}, 1, "sigma > 0"},
                      ParamCase{MfType::kGaussmf, {-1, 1}, 1, "sigma > 0"},
                      ParamCase{MfType::kGauss2mf, {1, 0, 0, 1}, 1, "both sigmas > 0"},
                      ParamCase{MfType::kGbellmf, {0, 2, 1}, 1, "a != 0"},
                      ParamCase{MfType::kGbellmf, {1, 0, 1}, 1, "b > 0"},
                      ParamCase{MfType::kSmf, {3, 1}, 1, "a < b"}, ParamCase{MfType::kZmf, {1, 1}, 1, "a < b"},
                      ParamCase{MfType::kPimf, {0, 1, 3, 2}, 1, "c < d"},
                      ParamCase{MfType::kSigmf, {0, 1}, 1, ""},
                      ParamCase{MfType::kConstant, {1, 2}, 2, "constant needs 1 parameter, got 2"},
                      ParamCase{MfType::kLinear, {1, 2}, 2, "linear needs 3 parameters, got 2"},
                      ParamCase{MfType::kLinear, {1, 2, 3}, 2, ""},
                      ParamCase{MfType::kGaussmf, {1, std::nan("")}, 1, "finite"}));

}  // namespace
}  // namespace inspect::fuzzy
