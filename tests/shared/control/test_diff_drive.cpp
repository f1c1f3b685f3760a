// Differential-drive kinematics: convention, round trips, limits, odometry.
#include <gtest/gtest.h>

#include <numbers>

#include "shared/control/diff_drive.hpp"

using namespace inspect::control;

namespace {
constexpr double kR = 0.2, kL = 0.438;
}

struct TwistCase {
  double v, w;
};
inline void PrintTo(const TwistCase& c, std::ostream* os) { *os << "v=" << c.v << " w=" << c.w; }
class DiffDriveRoundTrip : public ::testing::TestWithParam<TwistCase> {};

TEST_P(DiffDriveRoundTrip, TwistToWheelsAndBack) {
  const auto c = GetParam();
  const auto w = wheelsFromTwist({c.v, c.w}, kR, kL);
  const auto t = twistFromWheels(w, kR, kL);
  EXPECT_NEAR(t.v_m_s, c.v, 1e-12);
  EXPECT_NEAR(t.w_rad_s, c.w, 1e-12);
}
INSTANTIATE_TEST_SUITE_P(Cases, DiffDriveRoundTrip,
                         ::testing::Values(TwistCase{0, 0}, TwistCase{0.5, 0}, TwistCase{-0.5, 0}, TwistCase{0, 1},
                                           TwistCase{0.3, -0.7}, TwistCase{1.0, 2.0}));

TEST(DiffDrive, FasterRightWheelTurnsLeft) {
  const auto t = twistFromWheels({1.0, 2.0}, kR, kL);
  EXPECT_GT(t.w_rad_s, 0.0);  // counter-clockwise = left turn
  const auto w = wheelsFromTwist({0.0, 1.0}, kR, kL);
  EXPECT_LT(w.left_rad_s, 0.0);
  EXPECT_GT(w.right_rad_s, 0.0);
  EXPECT_NEAR(w.right_rad_s, kL / 2 / kR, 1e-12);
}

TEST(DiffDrive, LimitKeepsTurningRadius) {
  const Twist t{1.5, 1.0};
  const auto l = limitTwist(t, kR, kL, 5.0);
  const auto w = wheelsFromTwist(l, kR, kL);
  EXPECT_NEAR(std::max(std::abs(w.left_rad_s), std::abs(w.right_rad_s)), 5.0, 1e-9);
  EXPECT_NEAR(l.v_m_s / l.w_rad_s, t.v_m_s / t.w_rad_s, 1e-9);
}

TEST(DiffDrive, WrapAngle) {
  EXPECT_NEAR(wrapAngle(3 * std::numbers::pi / 2), -std::numbers::pi / 2, 1e-12);
  EXPECT_NEAR(wrapAngle(-3 * std::numbers::pi / 2), std::numbers::pi / 2, 1e-12);
  EXPECT_NEAR(wrapAngle(0.1), 0.1, 1e-15);
  EXPECT_EQ(wrapAngle(std::nan("")), 0.0);
}

TEST(DiffDrive, OdometryClosesAQuarterCircle) {
  // Drive a quarter circle of radius 1 m in 1000 steps: should end at (1, 1, pi/2).
  Pose2 p;
  const double R = 1.0, arc = std::numbers::pi / 2;
  const int n = 1000;
  for (int i = 0; i < n; ++i) {
    const double ds = R * arc / n;
    const double dth = arc / n;
    p = integrateOdometry(p, ds - dth * kL / 2, ds + dth * kL / 2, kL);
  }
  EXPECT_NEAR(p.x_m, 1.0, 1e-6);
  EXPECT_NEAR(p.y_m, 1.0, 1e-6);
  EXPECT_NEAR(p.theta_rad, arc, 1e-9);
}
