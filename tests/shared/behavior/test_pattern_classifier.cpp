// Pattern classification (Table 1 patterns) with hysteresis.
#include <gtest/gtest.h>

#include <random>

#include "shared/behavior/pattern_classifier.hpp"

using namespace inspect;
using behavior::Pattern;

struct RawCase {
  const char* name;
  double x, y, vx, vy;
  Pattern want;
};
inline void PrintTo(const RawCase& c, std::ostream* os) { *os << c.name; }
class RawPattern : public ::testing::TestWithParam<RawCase> {};

TEST_P(RawPattern, Classifies) {
  const auto& c = GetParam();
  EXPECT_EQ(behavior::rawPattern(c.x, c.y, c.vx, c.vy, Pattern::kNone, {}), c.want) << c.name;
}
INSTANTIATE_TEST_SUITE_P(
    Table, RawPattern,
    ::testing::Values(RawCase{"crossing_left_to_right", 3, 1, 0, -0.5, Pattern::kCrossing},
                      RawCase{"crossing_right_to_left", 2, -1, 0.05, 0.5, Pattern::kCrossing},
                      RawCase{"encountering_offset", 4, 0.8, -0.5, 0, Pattern::kEncountering},
                      RawCase{"confronting_ahead", 4, 0.1, -0.5, 0.02, Pattern::kConfronting},
                      RawCase{"leading_ahead", 2, 0.2, 0.4, 0, Pattern::kLeading},
                      RawCase{"standing", 2, 0, 0.05, 0, Pattern::kNone},
                      RawCase{"behind", -2, 0, 0.5, 0, Pattern::kNone},
                      RawCase{"far_to_the_side", 2, 3, -0.5, 0, Pattern::kNone},
                      RawCase{"diagonal_gap_keeps_none", 3, 0, -0.45, -0.23, Pattern::kNone},
                      RawCase{"leading_beside_is_none", 2, 1.0, 0.4, 0, Pattern::kNone}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(PatternClassifier, HysteresisBandKeepsThePreviousPattern) {
  // 27 deg off opposite: between "opposite" (<= 25 deg off) and "crossing" (>= 30 deg off).
  EXPECT_EQ(behavior::rawPattern(3, 0.1, -0.45, -0.23, Pattern::kConfronting, {}), Pattern::kConfronting);
  EXPECT_EQ(behavior::rawPattern(3, 0.1, -0.45, -0.23, Pattern::kCrossing, {}), Pattern::kCrossing);
}

TEST(PatternClassifier, NeedsADwellAndDoesNotFlickerOnNoise) {
  behavior::PatternClassifier pc;
  std::mt19937 rng(1);
  std::normal_distribution<double> heading(0.0, 0.15);  // ~9 deg of heading noise
  const control::Pose2 robot{0, 0, 0};
  // An oncoming person slightly offset: noise pushes single samples across the
  // confronting/encountering lateral threshold only rarely; the output must settle.
  int changes = 0;
  Pattern last = Pattern::kNone;
  for (int k = 0; k < 300; ++k) {
    const double a = 3.14159 + heading(rng);
    const Pattern p = pc.step(robot, 4.0 - 0.005 * k, 0.15, 0.5 * std::cos(a), 0.5 * std::sin(a), 0.01);
    if (k < 25) {
      EXPECT_EQ(p, Pattern::kNone) << "not before the dwell";
    }
    if (p != last) ++changes;
    last = p;
  }
  EXPECT_EQ(last, Pattern::kConfronting);
  EXPECT_LE(changes, 2);
  EXPECT_EQ(pc.switches(), static_cast<uint64_t>(changes));
}

TEST(PatternClassifier, RobotHeadingIsTakenIntoAccount) {
  behavior::PatternClassifier pc;
  // Robot facing +y; a person ahead of it (at y = 3) walking towards it (-y).
  const control::Pose2 robot{0, 0, 1.5707963};
  Pattern p = Pattern::kNone;
  for (int k = 0; k < 50; ++k) p = pc.step(robot, 0.05, 3.0, 0.0, -0.5, 0.01);
  EXPECT_EQ(p, Pattern::kConfronting);
  for (int k = 0; k < 50; ++k) p = pc.stepNone(0.01);
  EXPECT_EQ(p, Pattern::kNone);
}
