// Eq 10 error, Eq 12 auxiliary controller, reference paths.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "shared/control/reference_path.hpp"
#include "shared/control/tracking_controller.hpp"

using namespace inspect::control;

TEST(TrackingError, SignsInTheRobotFrame) {
  const Pose2 ref{0, 0, 0};
  EXPECT_NEAR(trackingError({1, 0, 0}, ref).x_m, 1.0, 1e-12);         // ahead
  EXPECT_NEAR(trackingError({0, 1, 0}, ref).y_m, 1.0, 1e-12);         // to the left
  EXPECT_NEAR(trackingError({0, 0, 0.3}, ref).theta_rad, 0.3, 1e-12);
  // Rotated robot: the error is expressed in ITS frame (Eq 10).
  const auto e = trackingError({0, 1, std::numbers::pi / 2}, ref);
  EXPECT_NEAR(e.x_m, 1.0, 1e-12);
  EXPECT_NEAR(e.y_m, 0.0, 1e-12);
}

TEST(AuxiliaryControl, CorrectsEachErrorTheRightWay) {
  const ReferenceState ref{{0, 0, 0}, 0.5, 0.0};
  const AuxiliaryGains g;
  EXPECT_LT(auxiliaryControl(trackingError({0.2, 0, 0}, ref.pose), ref, g).v_m_s, 0.5);      // ahead: slow down
  EXPECT_LT(auxiliaryControl(trackingError({0, 0.2, 0}, ref.pose), ref, g).w_rad_s, 0.0);    // left: turn right
  EXPECT_LT(auxiliaryControl(trackingError({0, 0, 0.2}, ref.pose), ref, g).w_rad_s, 0.0);    // heading left: turn right
  const auto zero = auxiliaryControl(TrackingError{}, ref, g);
  EXPECT_DOUBLE_EQ(zero.v_m_s, 0.5);
  EXPECT_DOUBLE_EQ(zero.w_rad_s, 0.0);
}

TEST(AuxiliaryControl, ClosedLoopOnAUnicycleConvergesToTheCircle) {
  // Ideal unicycle, start 0.3 m off the circle and 0.2 rad off heading.
  const auto path = makeCircle({0, 0, 0}, 3.5, 0.5);
  PathProgress prog;
  Pose2 p{0.0, -0.3, 0.2};
  double err_end = 0;
  for (int k = 0; k < 4000; ++k) {
    const auto ref = advance(*path, prog, 1.0, 0.01);
    const auto tw = auxiliaryControl(trackingError(p, ref.pose), ref, AuxiliaryGains{});
    p.x_m += tw.v_m_s * std::cos(p.theta_rad) * 0.01;
    p.y_m += tw.v_m_s * std::sin(p.theta_rad) * 0.01;
    p.theta_rad = wrapAngle(p.theta_rad + tw.w_rad_s * 0.01);
    err_end = trackingError(p, ref.pose).position_m();
  }
  EXPECT_LT(err_end, 0.005);
}

TEST(ReferencePath, CircleGeometry) {
  const auto c = makeCircle({0, 0, 0}, 3.5, 0.5);
  EXPECT_NEAR(c->length_m(), 2 * std::numbers::pi * 3.5, 1e-9);
  const auto quarter = c->at(c->length_m() / 4);
  EXPECT_NEAR(quarter.pose.x_m, 3.5, 1e-9);
  EXPECT_NEAR(quarter.pose.y_m, 3.5, 1e-9);
  EXPECT_NEAR(quarter.pose.theta_rad, std::numbers::pi / 2, 1e-9);
  EXPECT_NEAR(c->at(c->length_m() / 2).pose.y_m, 7.0, 1e-9);
  const auto cw = makeCircle({0, 0, 0}, -2.0, 0.5);
  EXPECT_NEAR(cw->at(cw->length_m() / 4).pose.y_m, -2.0, 1e-9);
  EXPECT_LT(cw->at(1.0).curvature_1_m, 0.0);
}

TEST(ReferencePath, LineAndWaypoints) {
  const auto l = makeLine({1, 1, std::numbers::pi / 2}, 2.0, 0.4);
  EXPECT_NEAR(l->at(2.0).pose.y_m, 3.0, 1e-12);
  const auto w = makeTimedWaypoints({{0, 0, 0}, {2, 1, 0}, {4, 1, 1}});
  EXPECT_NEAR(w->length_m(), 2.0, 1e-12);
  EXPECT_NEAR(w->at(0.5).speed_m_s, 0.5, 1e-12);
  EXPECT_NEAR(w->at(1.5).pose.theta_rad, std::numbers::pi / 2, 1e-12);
  EXPECT_THROW(makeTimedWaypoints({{0, 0, 0}, {0, 1, 0}}), std::invalid_argument);
  EXPECT_THROW(makeCircle({0, 0, 0}, 0.0, 0.5), std::invalid_argument);
}

TEST(ReferencePath, SpeedFactorSlowsProgressAndZeroStops) {
  const auto l = makeLine({0, 0, 0}, 10.0, 0.5);
  PathProgress a, b;
  for (int k = 0; k < 100; ++k) {
    advance(*l, a, 1.0, 0.01);
    advance(*l, b, 0.5, 0.01);
  }
  EXPECT_NEAR(a.s_m, 0.5, 1e-9);
  EXPECT_NEAR(b.s_m, 0.25, 1e-9);
  const double s = b.s_m;
  const auto r = advance(*l, b, 0.0, 0.01);
  EXPECT_DOUBLE_EQ(b.s_m, s);
  EXPECT_DOUBLE_EQ(r.v_m_s, 0.0);
}
