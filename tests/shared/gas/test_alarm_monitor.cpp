// The robot's gas alarm logic: thresholds with hysteresis and minimum
// duration, no chattering on noise, low-side (O2) alarms, sensor faults.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "shared/gas/alarm_monitor.hpp"

using namespace inspect;
using gas::AlarmLevel;
using gas::AlarmMonitor;
using gas::AlarmTransition;

namespace {

constexpr double kDt = 0.01;  // 100 Hz sensor frames

config::GasConfig cfg() { return config::defaultGasConfig(); }

// Raw slots for CH4 = v %LEL, O2 at its background, others 0 (with a count of wobble so nothing reads stuck).
std::array<uint16_t, 4> frame(double ch4, int k, double o2 = 20.9) {
  const int w = k % 2;
  return {static_cast<uint16_t>(std::lround(ch4 / 0.01) + w), static_cast<uint16_t>(w),
          static_cast<uint16_t>(w), static_cast<uint16_t>(std::lround(o2 / 0.01) + w)};
}

struct Feed {
  AlarmMonitor m{cfg()};
  std::vector<AlarmTransition> out;
  double t = 0.0;
  int k = 0;
  void feed(double seconds, double ch4, double o2 = 20.9) {
    const int n = static_cast<int>(std::lround(seconds / kDt));
    for (int i = 0; i < n; ++i, ++k, t += kDt) {
      const auto f = frame(ch4, k, o2);
      m.update(f, t, out);
    }
  }
  int count(AlarmLevel l, bool active, int channel = 0) const {
    int n = 0;
    for (const auto& a : out) n += a.level == l && a.active == active && a.channel == channel;
    return n;
  }
};

}  // namespace

TEST(AlarmMonitor, QuietBelowThresholds) {
  Feed r;
  r.feed(30.0, 5.0);
  EXPECT_TRUE(r.out.empty());
  EXPECT_NEAR(r.m.value(0), 5.0, 0.011);
  EXPECT_NEAR(r.m.value(3), 20.9, 0.011);
  EXPECT_FALSE(r.m.anyHigh());
}

TEST(AlarmMonitor, RaisesAfterMinDurationAndClearsPastHysteresis) {
  Feed r;
  r.feed(1.0, 0.0);
  const double t_cross = r.t;
  // The 0.5 s filter reaches A1 (10) 0.5 ln 6 = 0.90 s after a step from 0 to 12;
  // then min_duration (1 s) must pass.
  r.feed(1.8, 12.0);
  EXPECT_TRUE(r.out.empty());
  r.feed(0.2, 12.0);
  ASSERT_EQ(r.count(AlarmLevel::Low, true), 1);
  const auto& raised = r.out.front();
  EXPECT_NEAR(raised.since_s - t_cross, 0.5 * std::log(6.0) + 1.0, 0.02);
  EXPECT_DOUBLE_EQ(raised.threshold, 10.0);
  EXPECT_NEAR(raised.value, 12.0, 0.011);
  EXPECT_EQ(r.count(AlarmLevel::High, true), 0);

  r.feed(3.0, 25.0);  // A2 as well
  EXPECT_EQ(r.count(AlarmLevel::High, true), 1);
  EXPECT_TRUE(r.m.anyHigh());
  r.feed(3.0, 19.0);  // below A2 but not past its hysteresis (20 - 2): A2 holds
  EXPECT_EQ(r.count(AlarmLevel::High, false), 0);
  r.feed(3.0, 17.0);  // past it: A2 clears after 1 s, A1 stays
  EXPECT_EQ(r.count(AlarmLevel::High, false), 1);
  EXPECT_EQ(r.count(AlarmLevel::Low, false), 0);
  r.feed(3.0, 7.0);
  ASSERT_EQ(r.count(AlarmLevel::Low, false), 1);
  // Raise and clear share the id; the clear carries the peak.
  for (const auto& a : r.out) {
    if (a.level == AlarmLevel::High && !a.active) {
      EXPECT_NEAR(a.peak, 25.0, 0.02);
      std::vector<AlarmTransition> act;
      r.m.active(act);
      EXPECT_TRUE(act.empty());
    }
  }
  uint64_t low_id = 0;
  for (const auto& a : r.out)
    if (a.level == AlarmLevel::Low) {
      if (low_id == 0) low_id = a.id;
      EXPECT_EQ(a.id, low_id);
    }
}

// A reading wandering around `mean` with sd 1 %LEL (3x the sensor's noise) for 5 minutes.
static std::vector<AlarmTransition> noisyCh4(double mean) {
  AlarmMonitor m(cfg());
  std::vector<AlarmTransition> out;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (int k = 0; k < 30000; ++k) {
    const double v = mean + noise(rng);
    const std::array<uint16_t, 4> f{static_cast<uint16_t>(std::lround(std::max(0.0, v) / 0.01)),
                                    static_cast<uint16_t>(k % 2), static_cast<uint16_t>(k % 2),
                                    static_cast<uint16_t>(2090 + k % 2)};
    m.update(f, k * kDt, out);
  }
  return out;
}

TEST(AlarmMonitor, NoChatteringOnNoiseAroundTheThreshold) {
  // Just above A1 (10): raised once and never cleared or raised again; just below: never raised.
  const auto above = noisyCh4(10.5);
  ASSERT_EQ(above.size(), 1u);
  EXPECT_TRUE(above[0].active);
  EXPECT_EQ(above[0].level, AlarmLevel::Low);
  EXPECT_LT(above[0].since_s, 3.0);
  EXPECT_TRUE(noisyCh4(9.5).empty());
}

TEST(AlarmMonitor, ShortSpikesDoNotRaise) {
  Feed r;
  r.feed(1.0, 0.0);
  for (int i = 0; i < 20; ++i) {
    r.feed(0.5, 30.0);  // through the filter: above A1 for 0.6 s, under min_duration
    r.feed(1.0, 0.0);
  }
  EXPECT_TRUE(r.out.empty());
  for (const auto& a : r.out) ADD_FAILURE() << gas::levelName(a.level) << " " << a.fault << " at " << a.t_s;
}

TEST(AlarmMonitor, OxygenIsALowSideAlarm) {
  Feed r;
  r.feed(2.0, 0.0, 20.9);
  r.feed(2.0, 0.0, 19.0);  // below A1 19.5
  EXPECT_EQ(r.count(AlarmLevel::Low, true, 3), 1);
  EXPECT_EQ(r.count(AlarmLevel::High, true, 3), 0);
  r.feed(2.0, 0.0, 17.5);  // below A2 18
  EXPECT_EQ(r.count(AlarmLevel::High, true, 3), 1);
  r.feed(2.0, 0.0, 18.2);  // not yet back past 18 + 0.3
  EXPECT_EQ(r.count(AlarmLevel::High, false, 3), 0);
  r.feed(2.0, 0.0, 20.5);
  EXPECT_EQ(r.count(AlarmLevel::High, false, 3), 1);
  EXPECT_EQ(r.count(AlarmLevel::Low, false, 3), 1);
  for (const auto& a : r.out)
    if (a.level == AlarmLevel::High && !a.active) {
      EXPECT_NEAR(a.peak, 17.5, 0.02);  // worst = lowest
    }
}

TEST(AlarmMonitor, StuckSensorRaisesAFaultAndFreezesTheAlarms) {
  AlarmMonitor m(cfg());
  std::vector<AlarmTransition> out;
  double t = 0.0;
  for (int k = 0; k < 500; ++k, t += kDt) {
    const auto f = frame(3.0, k);
    m.update(f, t, out);
  }
  // CH4 freezes at exactly one raw value.
  for (int k = 0; k < 1200; ++k, t += kDt) {
    auto f = frame(3.0, k);
    f[0] = 300;
    m.update(f, t, out);
  }
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].level, AlarmLevel::SensorFault);
  EXPECT_STREQ(out[0].fault, "stuck");
  EXPECT_EQ(out[0].channel, 0);
  EXPECT_NEAR(out[0].since_s, 5.0 + 10.0, 0.05);  // stuck_s = 10
  // It moves again: the fault clears at once.
  auto f = frame(3.0, 1);
  f[0] = 301;
  m.update(f, t, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_FALSE(out[1].active);
}

TEST(AlarmMonitor, DropoutAndMissingFramesAreNoDataFaults) {
  AlarmMonitor m(cfg());
  std::vector<AlarmTransition> out;
  double t = 0.0;
  for (int k = 0; k < 300; ++k, t += kDt) {
    const auto f = frame(25.0, k);  // A1 and A2 up
    m.update(f, t, out);
  }
  ASSERT_EQ(out.size(), 2u);
  out.clear();
  for (int k = 0; k < 100; ++k, t += kDt) {
    auto f = frame(25.0, k);
    f[0] = config::kGasNoData;
    m.update(f, t, out);
  }
  ASSERT_EQ(out.size(), 1u);
  EXPECT_STREQ(out[0].fault, "no_data");
  EXPECT_TRUE(std::isnan(m.value(0)));
  EXPECT_TRUE(m.anyHigh());  // no reading is no all-clear
  out.clear();
  for (int k = 0; k < 100; ++k, t += kDt) m.noFrames(t, out);
  // Every other channel goes no-data too.
  EXPECT_EQ(out.size(), 3u);
}

TEST(AlarmMonitor, OutOfRangeIsAFaultAndStillAlarms) {
  Feed r;
  r.feed(2.0, 150.0);  // CH4 range 0..100 %LEL
  EXPECT_EQ(r.count(AlarmLevel::SensorFault, true), 1);
  EXPECT_EQ(r.count(AlarmLevel::High, true), 1);
  bool saw = false;
  for (const auto& a : r.out) saw |= std::string(a.fault) == "out_of_range";
  EXPECT_TRUE(saw);
}

TEST(AlarmMonitor, CleanAirAtZeroIsNotStuck) {
  // A sensor with zero suppression reads exactly 0 in clean air for minutes.
  AlarmMonitor m(cfg());
  std::vector<AlarmTransition> out;
  for (int k = 0; k < 6000; ++k) {
    const std::array<uint16_t, 4> f{0, 0, 0, static_cast<uint16_t>(2090 + k % 2)};
    m.update(f, k * kDt, out);
  }
  EXPECT_TRUE(out.empty()) << gas::levelName(out.front().level) << " " << out.front().fault;
}

TEST(AlarmMonitor, ADropoutRestartsTheRaiseTimer) {
  // 0.8 s above A1, a 0.6 s dropout, then 0.3 s above A1: never 1 s in a row.
  Feed r;
  r.feed(1.0, 0.0);
  r.feed(1.7, 12.0);  // the filter crosses 10 after 0.9 s: 0.8 s of the 1 s counted
  for (int i = 0; i < 60; ++i, r.t += kDt, ++r.k) {
    auto f = frame(12.0, r.k);
    f[0] = config::kGasNoData;
    r.m.update(f, r.t, r.out);
  }
  const auto faults = r.count(AlarmLevel::SensorFault, true);
  r.feed(0.3, 12.0);
  EXPECT_EQ(r.count(AlarmLevel::Low, true), 0) << "the timer started over after the dropout";
  EXPECT_EQ(faults, 1);
}
