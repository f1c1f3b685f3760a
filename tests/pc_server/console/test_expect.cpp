// expect syntax and comparison, table-driven.
#include <gtest/gtest.h>

#include "pc_server/console/expect_check.hpp"
#include "pc_server/console/text_util.hpp"

using namespace inspect::server;

namespace {

struct ParseOk {
  const char* line;
  const char* field;
  ExpectOp op;
  double value;
  double tol;
  double within_s;
};

inline void PrintTo(const ParseOk& c, std::ostream* os) { *os << '"' << c.line << '"'; }

class ExpectParseOk : public ::testing::TestWithParam<ParseOk> {};

TEST_P(ExpectParseOk, Parses) {
  const auto& p = GetParam();
  const auto r = parseExpect(splitWords(p.line));
  ASSERT_TRUE(std::holds_alternative<ExpectSpec>(r)) << std::get<std::string>(r);
  const auto& s = std::get<ExpectSpec>(r);
  EXPECT_EQ(s.field, p.field);
  EXPECT_EQ(s.op, p.op);
  EXPECT_DOUBLE_EQ(s.value, p.value);
  EXPECT_DOUBLE_EQ(s.tol, p.tol);
  EXPECT_DOUBLE_EQ(s.within_s, p.within_s);
  EXPECT_EQ(s.has_within, p.within_s > 0);
}

INSTANTIATE_TEST_SUITE_P(
    Table, ExpectParseOk,
    ::testing::Values(ParseOk{"x == 1", "x", ExpectOp::kEq, 1, 0, 0}, ParseOk{"y != -2.5", "y", ExpectOp::kNe, -2.5, 0, 0},
                      ParseOk{"v < 0.5", "v", ExpectOp::kLt, 0.5, 0, 0}, ParseOk{"w <= 1e-3", "w", ExpectOp::kLe, 1e-3, 0, 0},
                      ParseOk{"battery > 20", "battery", ExpectOp::kGt, 20, 0, 0},
                      ParseOk{"robots >= 2 within 5", "robots", ExpectOp::kGe, 2, 0, 5},
                      ParseOk{"x ~ 2.0 0.05", "x", ExpectOp::kNear, 2.0, 0.05, 0},
                      ParseOk{"x ~ 2.0 +- 0.05 within 1.5", "x", ExpectOp::kNear, 2.0, 0.05, 1.5},
                      ParseOk{"mode == ESTOP", "mode", ExpectOp::kEq, 3, 0, 0},
                      ParseOk{"mode != teleop within 2", "mode", ExpectOp::kNe, 2, 0, 2},
                      ParseOk{"faults == 0x10", "faults", ExpectOp::kEq, 16, 0, 0}));

struct ParseBad {
  const char* line;
  const char* message;
};

inline void PrintTo(const ParseBad& c, std::ostream* os) { *os << '"' << c.line << '"'; }

class ExpectParseBad : public ::testing::TestWithParam<ParseBad> {};

TEST_P(ExpectParseBad, SaysWhatIsWrong) {
  const auto r = parseExpect(splitWords(GetParam().line));
  ASSERT_TRUE(std::holds_alternative<std::string>(r)) << GetParam().line;
  EXPECT_NE(std::get<std::string>(r).find(GetParam().message), std::string::npos) << std::get<std::string>(r);
}

INSTANTIATE_TEST_SUITE_P(Table, ExpectParseBad,
                         ::testing::Values(ParseBad{"", "too few words"}, ParseBad{"x ==", "too few words"},
                                           ParseBad{"speed > 1", "unknown field 'speed'"},
                                           ParseBad{"x => 1", "unknown operator '=>'"},
                                           ParseBad{"x == one", "'one' is not a number"},
                                           ParseBad{"mode == DRIVING", "or a mode"},
                                           ParseBad{"x ~ 2", "'~' needs a tolerance"},
                                           ParseBad{"x ~ 2 within 3", "'~' needs a tolerance"},
                                           ParseBad{"x ~ 2 -0.1", "is not a number >= 0"},
                                           ParseBad{"x == 2 0.1", "only allowed with '~'"},
                                           ParseBad{"x == 2 within", "needs a number of seconds"},
                                           ParseBad{"x == 2 within soon", "not a number of seconds"},
                                           ParseBad{"x == 2 within 1 extra", "unexpected 'extra'"},
                                           ParseBad{"x == 2 sometime", "unexpected 'sometime'"}));

}  // namespace

TEST(ExpectCompare, EveryOperator) {
  EXPECT_TRUE(compare(ExpectOp::kEq, 1, 1, 0));
  EXPECT_FALSE(compare(ExpectOp::kEq, 1, 1.0001, 0));
  EXPECT_TRUE(compare(ExpectOp::kNe, 1, 2, 0));
  EXPECT_TRUE(compare(ExpectOp::kLt, 1, 2, 0));
  EXPECT_FALSE(compare(ExpectOp::kLt, 2, 2, 0));
  EXPECT_TRUE(compare(ExpectOp::kLe, 2, 2, 0));
  EXPECT_TRUE(compare(ExpectOp::kGt, 3, 2, 0));
  EXPECT_FALSE(compare(ExpectOp::kGt, 2, 2, 0));
  EXPECT_TRUE(compare(ExpectOp::kGe, 2, 2, 0));
  EXPECT_TRUE(compare(ExpectOp::kNear, 1.96, 2.0, 0.05));
  EXPECT_TRUE(compare(ExpectOp::kNear, 2.04, 2.0, 0.05));
  EXPECT_FALSE(compare(ExpectOp::kNear, 1.93, 2.0, 0.05));
  EXPECT_FALSE(compare(ExpectOp::kNear, 2.06, 2.0, 0.05));
}

TEST(ExpectDescribe, ShowsWhatWasWanted) {
  const auto s = std::get<ExpectSpec>(parseExpect(splitWords("x ~ 2.0 0.05 within 3")));
  EXPECT_EQ(describeWanted(s), "~ 2.0 +- 0.05 within 3 s");
}

TEST(TextUtil, StrictNumbers) {
  EXPECT_EQ(parseNumber("1.5"), 1.5);
  EXPECT_EQ(parseNumber("-2"), -2.0);
  EXPECT_FALSE(parseNumber(""));
  EXPECT_FALSE(parseNumber("1.5x"));
  EXPECT_FALSE(parseNumber("inf"));
  EXPECT_FALSE(parseNumber("0x10"));
  EXPECT_FALSE(parseNumber("1e999"));
  EXPECT_EQ(parseInteger("0x10"), 16);
  EXPECT_EQ(parseInteger("-7"), -7);
  EXPECT_FALSE(parseInteger("7.5"));
  EXPECT_EQ(fmtShort(1.930), "1.93");
  EXPECT_EQ(fmtShort(2.0), "2");
  EXPECT_EQ(fmtShort(-0.0001), "0");
  EXPECT_EQ(fmtSigned(0.3), "+0.30");
  EXPECT_EQ(fmtSigned(-0.0001), "+0.00");
}
