// The camera stream's rate adaptation (shared/video/rate_controller.hpp):
// the GCC loss rule, the RTT guard, the report timeout, the level ladder.
#include <gtest/gtest.h>

#include "shared/video/rate_controller.hpp"

namespace inspect::video {
namespace {

constexpr uint64_t kS = 1'000'000;  // one second in microseconds

RateSettings settings() {
  RateSettings s;
  s.start_kbps = 2000;
  s.min_kbps = 300;
  s.max_kbps = 4000;
  return s;
}

TEST(RateController, HoldsTheStartRateUntilTheFirstReport) {
  RateController rc(settings(), 10 * kS);
  for (uint64_t t = 10; t < 40; ++t) rc.tick(t * kS);
  EXPECT_EQ(rc.state().kbps, 2000);
  EXPECT_EQ(rc.state().level, 0);
  EXPECT_EQ(rc.state().reason, "start");
  EXPECT_EQ(rc.state().changes, 0u);
}

TEST(RateController, CleanReportsRaiseTheRateByEightPercentASecondUpToTheCeiling) {
  RateController rc(settings(), 0);
  rc.onReport(1 * kS, 0.0, 10.0);
  EXPECT_EQ(rc.state().kbps, 2160);
  EXPECT_EQ(rc.state().reason, "loss 0.0 % < 2 %: x1.08/s");
  rc.onReport(3 * kS, 0.01, 10.0);  // two seconds later: x1.08^2
  EXPECT_EQ(rc.state().kbps, 2519);
  for (uint64_t t = 4; t < 20; ++t) rc.onReport(t * kS, 0.0, 10.0);
  EXPECT_EQ(rc.state().kbps, 4000);
}

TEST(RateController, LossBetweenTwoAndTenPercentHoldsTheRate) {
  RateController rc(settings(), 0);
  for (uint64_t t = 1; t < 30; ++t) rc.onReport(t * kS, t % 2 ? 0.02 : 0.10, 10.0);
  EXPECT_EQ(rc.state().kbps, 2000);
  EXPECT_EQ(rc.state().changes, 0u);
}

TEST(RateController, HeavyLossCutsByHalfTheLossFraction) {
  RateController rc(settings(), 0);
  rc.onReport(1 * kS, 0.20, 10.0);
  EXPECT_EQ(rc.state().kbps, 1800);  // x (1 - 0.5 x 0.2)
  EXPECT_EQ(rc.state().reason, "loss 20.0 % > 10 %: x0.90");
  EXPECT_EQ(rc.state().changed_us, 1 * kS);
}

TEST(RateController, BelowTheFloorTheFrameRateThenTheSizeStepDownAndComeBackInReverse) {
  RateController rc(settings(), 0);
  uint64_t t = 1;
  int first_level1 = -1, first_level2 = -1;
  for (; t < 60; ++t) {
    rc.onReport(t * kS, 0.30, 10.0);
    EXPECT_GE(rc.state().kbps, 300);
    if (rc.state().level == 1 && first_level1 < 0) first_level1 = static_cast<int>(t);
    if (rc.state().level == 2 && first_level2 < 0) first_level2 = static_cast<int>(t);
  }
  // 2000 x 0.85^n < 300 after 12 reports; the size follows no sooner than 2 s later.
  EXPECT_EQ(first_level1, 12);
  EXPECT_GE(first_level2, first_level1 + 2);
  EXPECT_EQ(rc.state().level, 2);  // never below the last level
  EXPECT_EQ(rc.state().kbps, 300);
  // Clean again: 300 x 1.08^n >= 450 after 6 s: size first, then frame rate.
  int back_to_1 = -1, back_to_0 = -1;
  for (uint64_t u = t; u < t + 40; ++u) {
    rc.onReport(u * kS, 0.0, 10.0);
    if (rc.state().level == 1 && back_to_1 < 0) {
      back_to_1 = static_cast<int>(u - t);
      EXPECT_NE(rc.state().reason.find("size restored"), std::string::npos) << rc.state().reason;
    }
    if (rc.state().level == 0 && back_to_0 < 0) {
      back_to_0 = static_cast<int>(u - t);
      EXPECT_NE(rc.state().reason.find("frame rate restored"), std::string::npos) << rc.state().reason;
    }
  }
  EXPECT_EQ(back_to_1, 5);
  EXPECT_EQ(back_to_0, 11);
  EXPECT_EQ(rc.state().level, 0);
  EXPECT_GT(rc.state().kbps, 1000);
}

TEST(RateController, WithoutLevelsTheFloorHolds) {
  RateSettings s = settings();
  s.max_level = 0;
  RateController rc(s, 0);
  for (uint64_t t = 1; t < 40; ++t) rc.onReport(t * kS, 0.5, 10.0);
  EXPECT_EQ(rc.state().kbps, 300);
  EXPECT_EQ(rc.state().level, 0);
}

TEST(RateController, ARisingRoundTripCutsTheRate) {
  RateController rc(settings(), 0);
  rc.onReport(1 * kS, 0.05, 20.0);
  rc.onReport(2 * kS, 0.05, 60.0);  // x3 but only +40 ms: a jitter, held
  EXPECT_EQ(rc.state().kbps, 2000);
  rc.onReport(3 * kS, 0.05, 200.0);
  EXPECT_EQ(rc.state().kbps, 1700);
  EXPECT_EQ(rc.state().reason, "RTT 200 ms > 2 x least 20 ms: x0.85");
  // A long path (100 ms RTT from the start) is not a queue.
  RateController far(settings(), 0);
  for (uint64_t t = 1; t < 10; ++t) far.onReport(t * kS, 0.05, 100.0 + static_cast<double>(t));
  EXPECT_EQ(far.state().kbps, 2000);
}

TEST(RateController, LostFeedbackHalvesTheRateEveryTimeout) {
  RateController rc(settings(), 0);
  rc.onReport(1 * kS, 0.05, 10.0);
  rc.tick(3 * kS + kS / 2);
  EXPECT_EQ(rc.state().kbps, 2000);
  rc.tick(4 * kS);
  EXPECT_EQ(rc.state().kbps, 1000);
  EXPECT_EQ(rc.state().reason, "no receiver report for 3.0 s: x0.5");
  rc.tick(5 * kS);
  EXPECT_EQ(rc.state().kbps, 1000);
  rc.tick(7 * kS);
  EXPECT_EQ(rc.state().kbps, 500);
}

TEST(RateController, TheOperatorsRateIsTheNewCeiling) {
  RateController rc(settings(), 0);
  for (uint64_t t = 1; t < 15; ++t) rc.onReport(t * kS, 0.3, 10.0);
  ASSERT_GT(rc.state().level, 0);
  rc.setOperatorRate(20 * kS, 800);
  EXPECT_EQ(rc.state().kbps, 800);
  EXPECT_EQ(rc.state().level, 0);
  EXPECT_EQ(rc.state().reason, "operator: 800 kbit/s");
  for (uint64_t t = 21; t < 40; ++t) rc.onReport(t * kS, 0.0, 10.0);
  EXPECT_EQ(rc.state().kbps, 800);
  rc.setOperatorRate(40 * kS, 100);  // below the floor: the floor follows
  for (uint64_t t = 41; t < 60; ++t) rc.onReport(t * kS, 0.0, 10.0);
  EXPECT_EQ(rc.state().kbps, 100);
}

TEST(RateController, DisabledKeepsTheConfiguredRate) {
  RateSettings s = settings();
  s.enabled = false;
  RateController rc(s, 0);
  for (uint64_t t = 1; t < 20; ++t) {
    rc.onReport(t * kS, 0.5, 10.0 * static_cast<double>(t));
    rc.tick(t * kS + kS / 2);
  }
  EXPECT_EQ(rc.state().kbps, 2000);
  EXPECT_EQ(rc.state().changes, 0u);
}

TEST(RateController, ValidateNamesTheSetting) {
  RateSettings s = settings();
  EXPECT_EQ(validate(s), "");
  s.min_kbps = 5000;
  EXPECT_EQ(validate(s), "video.adapt.min_kbps: 5000 above max_kbps 4000");
  s = settings();
  s.max_kbps = 20;
  EXPECT_EQ(validate(s), "video.adapt.max_kbps: 20 out of range [50, 50000]");
}

}  // namespace
}  // namespace inspect::video
