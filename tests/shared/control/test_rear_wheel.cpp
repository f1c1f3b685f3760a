// Eqs 4-6: turning radius and rear wheel angle, with the paper's check values.
#include <gtest/gtest.h>

#include <numbers>

#include "shared/control/rear_wheel.hpp"

using namespace inspect::control;

namespace {
constexpr double kDeg = std::numbers::pi / 180.0;
const RearWheelGeometry kPaper{};
}  // namespace

TEST(RearWheel, PaperCheckValues) {
  // Paper: a 90 degree turn needs beta ~ 20 deg, w1/w2 ~ 1.44, R ~ 1.17-1.2 m.
  const double k = ratioFromRearAngle(20 * kDeg, kPaper);
  EXPECT_NEAR(k, 1.44, 0.01);
  EXPECT_NEAR(turningRadiusFromRatio(1.44, kPaper.track_m), 1.2, 0.02);
  EXPECT_NEAR(rearAngleFromRatio(1.44, kPaper) / kDeg, 20.0, 0.5);  // 19.7 deg: 1.44 is rounded
}

class RearWheelRoundTrip : public ::testing::TestWithParam<double> {};
TEST_P(RearWheelRoundTrip, BetaToRatioAndBack) {
  const double beta = GetParam() * kDeg;
  const double k = ratioFromRearAngle(beta, kPaper);
  EXPECT_NEAR(rearAngleFromRatio(k, kPaper), beta, 1e-9);
  // Eq 6 holds: tan(beta) = (L1 + L2 + L3 / cos(beta)) / R.
  const double r = turningRadiusFromRatio(k, kPaper.track_m);
  if (beta != 0.0) {
    EXPECT_NEAR(std::tan(beta), (kPaper.l1_m + kPaper.l2_m + kPaper.l3_m / std::cos(beta)) / r, 1e-9);
  }
}
INSTANTIATE_TEST_SUITE_P(Angles, RearWheelRoundTrip, ::testing::Values(0.0, 1.0, 5.0, 10.0, 20.0, 35.0, 50.0, -10.0, -20.0));

TEST(RearWheel, RadiusRatioRoundTripAndLimits) {
  for (double r : {0.3, 1.0, 1.2, 5.0, 100.0}) EXPECT_NEAR(turningRadiusFromRatio(ratioFromTurningRadius(r, 0.438), 0.438), r, 1e-9);
  EXPECT_TRUE(std::isinf(turningRadiusFromRatio(1.0, 0.438)));
  EXPECT_DOUBLE_EQ(turningRadiusFromRatio(-1.0, 0.438), 0.0);  // spin in place
  EXPECT_DOUBLE_EQ(rearAngleFromRatio(1.0, kPaper), 0.0);
  EXPECT_TRUE(std::isnan(rearAngleFromRatio(std::nan(""), kPaper)));
}
