// The identification profiles robots play for `identify` (shared/control/wheel_profile.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "shared/control/wheel_profile.hpp"

using namespace inspect::control;
using K = WheelProfileSegment::Kind;

TEST(WheelProfile, SegmentsPlayInOrderAndStopAtTheEnd) {
  const WheelProfile p({{K::kHold, 1.0}, {K::kStep, 2.0, -1.0, 1.0}, {K::kChirp, 4.0, 2.0, 2.0, 0.5, 0.5}}, 5.0);
  EXPECT_DOUBLE_EQ(p.duration_s(), 7.0);
  EXPECT_DOUBLE_EQ(p.at(0.5).left_rad_s, 0.0);
  EXPECT_DOUBLE_EQ(p.at(1.5).left_rad_s, -1.0);
  EXPECT_DOUBLE_EQ(p.at(1.5).right_rad_s, 1.0);
  // 0.5 Hz sine from t = 3: a quarter period later it peaks at the amplitude.
  EXPECT_NEAR(p.at(3.5).left_rad_s, 2.0, 1e-9);
  EXPECT_NEAR(p.at(4.0).left_rad_s, 0.0, 1e-9);
  EXPECT_DOUBLE_EQ(p.at(7.0).left_rad_s, 0.0);
  EXPECT_DOUBLE_EQ(p.at(-1.0).right_rad_s, 0.0);
  EXPECT_DOUBLE_EQ(p.at(std::nan("")).right_rad_s, 0.0);
}

TEST(WheelProfile, ChirpSweepsItsFrequency) {
  // Linear sweep 1 -> 3 Hz over 2 s: the phase reaches 2 pi (1*2 + 2*2/2) = 2 pi * 4, so zero crossings
  // come faster towards the end.
  const WheelProfile p({{K::kChirp, 2.0, 1.0, 1.0, 1.0, 3.0}}, 5.0);
  int crossings_first = 0, crossings_last = 0;
  double prev = p.at(0.0005).left_rad_s;
  for (int i = 1; i < 2000; ++i) {
    const double t = i * 0.001 + 0.0005;
    const double v = p.at(t).left_rad_s;
    if ((v > 0) != (prev > 0)) (t < 1.0 ? crossings_first : crossings_last)++;
    prev = v;
  }
  EXPECT_LT(crossings_first, crossings_last);
  EXPECT_EQ(crossings_first + crossings_last, 7);
}

TEST(WheelProfile, BadSegmentsAreRefusedNamingTheSegment) {
  auto msg = [](std::vector<WheelProfileSegment> s) {
    try {
      WheelProfile p(std::move(s), 5.0);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(msg({}).find("at least one segment"), std::string::npos);
  EXPECT_NE(msg({{K::kHold, 1.0}, {K::kStep, 0.0, 1, 1}}).find("segment 2 (step): duration_s"), std::string::npos);
  EXPECT_NE(msg({{K::kStep, 1.0, 6.0, 0.0}}).find("within +-5"), std::string::npos);
  EXPECT_NE(msg({{K::kStep, 1.0, std::nan(""), 0.0}}).find("finite"), std::string::npos);
  EXPECT_NE(msg({{K::kChirp, 1.0, 1.0, 1.0, 0.0, 2.0}}).find("chirp frequencies"), std::string::npos);
}

TEST(WheelProfile, StandardIdentificationSpinsOnTheSpotAndReturns) {
  const auto p = WheelProfile::standardIdentification(2.0, 5.0);
  EXPECT_GT(p.duration_s(), 20.0);
  EXPECT_LT(p.duration_s(), 60.0);
  // Net travel of the axle midpoint along its heading: sum of (l + r) / 2 dt = 0
  // (spins have l = -r; the straight steps cancel).
  double forward = 0.0, peak = 0.0;
  for (double t = 0.0; t < p.duration_s(); t += 0.001) {
    const auto w = p.at(t);
    forward += (w.left_rad_s + w.right_rad_s) / 2.0 * 0.001;
    peak = std::max(peak, std::abs(w.left_rad_s));
  }
  EXPECT_NEAR(forward, 0.0, 1e-6);
  EXPECT_DOUBLE_EQ(peak, 2.0);
  EXPECT_THROW(WheelProfile::standardIdentification(2.0, 0.0), std::invalid_argument);
}
