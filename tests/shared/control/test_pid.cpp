// PID (Eq 14): closed loop on a first-order plant, anti-windup, guards.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "shared/control/pid_controller.hpp"
#include "tests/shared/control/first_order.hpp"

using namespace inspect::control;

using inspect::test::FirstOrder;

TEST(Pid, ClosedLoopConvergesWithoutOffset) {
  PidConfig cfg;
  cfg.output_min = -10;
  cfg.output_max = 10;
  PidState s;
  FirstOrder plant{0.3};
  const PidGains g{9, 2, 3};
  int settled_at = -1;
  for (int k = 0; k < 3000; ++k) {
    plant.step(pidStep(cfg, g, s, 2.5, plant.y, 0.01), 0.01);
    if (settled_at < 0 && std::abs(plant.y - 2.5) < 0.025) settled_at = k;
  }
  EXPECT_NEAR(plant.y, 2.5, 1e-3) << "integral action removes the offset";
  EXPECT_GE(settled_at, 0);
  EXPECT_LT(settled_at, 600) << "within 6 s";
}

TEST(Pid, DerivativeActsOnMeasurementSoSetpointStepsDoNotKick) {
  PidConfig cfg;
  PidState s;
  const PidGains g{0, 0, 5};
  pidStep(cfg, g, s, 0.0, 1.0, 0.01);
  EXPECT_DOUBLE_EQ(pidStep(cfg, g, s, 100.0, 1.0, 0.01), 0.0);
}

TEST(Pid, AntiWindupRecoversQuickly) {
  PidConfig cfg;
  cfg.output_min = -1;
  cfg.output_max = 1;
  cfg.integral_limit = 5;
  PidState s;
  const PidGains g{1, 5, 0};
  // Saturated for 10 s with a large error: the integral must not run away.
  for (int k = 0; k < 1000; ++k) pidStep(cfg, g, s, 100.0, 0.0, 0.01);
  EXPECT_LE(std::abs(s.integral), 5.0);
  EXPECT_DOUBLE_EQ(s.output, 1.0);
  // Error reverses: output leaves saturation within a few steps.
  int k = 0;
  while (s.output >= 1.0 && k < 1000) {
    pidStep(cfg, g, s, -1.0, 0.0, 0.01);
    ++k;
  }
  EXPECT_LT(k, 3);
}

TEST(Pid, NonFiniteInputsHoldTheOutput) {
  PidConfig cfg;
  PidState s;
  const PidGains g{2, 1, 0};
  const double u = pidStep(cfg, g, s, 1.0, 0.0, 0.01);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_DOUBLE_EQ(pidStep(cfg, g, s, nan, 0.0, 0.01), u);
  EXPECT_DOUBLE_EQ(pidStep(cfg, g, s, 1.0, nan, 0.01), u);
  EXPECT_DOUBLE_EQ(pidStep(cfg, g, s, 1.0, 0.0, 0.0), u);
  EXPECT_DOUBLE_EQ(pidStep(cfg, {nan, 1, 0}, s, 1.0, 0.0, 0.01), u);
  EXPECT_TRUE(std::isfinite(s.integral));
}

TEST(Pid, GainChangesDoNotBumpTheOutput) {
  PidConfig cfg;
  PidState s;
  for (int k = 0; k < 100; ++k) pidStep(cfg, {1, 2, 0}, s, 1.0, 0.5, 0.01);
  const double before = s.output;
  // Same error, ki doubled: only the new increment uses the new ki.
  const double after = pidStep(cfg, {1, 4, 0}, s, 1.0, 0.5, 0.01);
  EXPECT_NEAR(after - before, 4 * 0.5 * 0.01, 1e-12);
}
