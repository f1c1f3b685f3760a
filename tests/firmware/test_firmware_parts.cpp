// The firmware core's parts on the host (docs/firmware.md): the speed loop,
// odometry, ultrasonic scheduler, anti-collision stop, analog inputs, button
// debounce and the camera mount's servos.
#include <gtest/gtest.h>

#include <cmath>

#include "firmware/core/analog_inputs.hpp"
#include "firmware/core/odometry.hpp"
#include "firmware/core/ptz_servo.hpp"
#include "firmware/core/ultrasonic.hpp"
#include "firmware/core/wheel_speed.hpp"
#include "firmware/host/settings_from_config.hpp"
#include "shared/config/robot_config.hpp"
#include "tests/firmware/motor_plant.hpp"
#include "tests/support/paths.hpp"

namespace inspect::firmware {
namespace {

McuSettings robotYaml() { return settingsFrom(config::loadRobotConfigFile(inspect::test::srcPath("config/robot.yaml"))); }

constexpr float kDt = 0.001f;

// Runs the loop against the plant for `seconds`; the largest speed seen.
float run(WheelSpeedLoop& loop, test::MotorPlant& m, float setpoint, float seconds, bool enabled = true) {
  float peak = -1e9f;
  for (int i = 0; i < static_cast<int>(seconds / kDt); ++i) {
    const float duty = loop.step(setpoint, enabled, m.counter());
    EXPECT_LE(std::fabs(duty), 1.0f);
    m.step(duty, !enabled, kDt);
    peak = std::max(peak, m.omega);
  }
  return peak;
}

TEST(WheelSpeedLoop, FollowsASetPointWithinTwoPercentAndItsEstimateWithinOne) {
  const McuSettings s = robotYaml();
  WheelSpeedLoop loop(s, kDt);
  test::MotorPlant m(s);
  const float peak = run(loop, m, 3.0f, 1.5f);
  EXPECT_NEAR(m.omega, 3.0f, 0.06f);
  EXPECT_LT(peak, 3.0f * 1.05f) << "overshoot";
  EXPECT_NEAR(loop.speedRadS(), m.omega, 0.03f);
  run(loop, m, -2.0f, 1.5f);  // and backwards, across the counter's wrap
  EXPECT_NEAR(m.omega, -2.0f, 0.04f);
}

TEST(WheelSpeedLoop, TheWheelAnswersAsTheReferenceModelWhateverTheMotor) {
  // The robot's response (robot.yaml motor.time_constant_s) from the
  // feed-forward alone on the nominal motor; a motor half as quick and 15 %
  // weaker (load, a low battery) brought to it by the PI, which is gentle (the
  // Pi's fuzzy-PID is the fast loop on the same wheel: docs/firmware.md).
  const McuSettings s = robotYaml();
  for (const float tau : {s.response_tau_s, 2.0f * s.response_tau_s}) {
    WheelSpeedLoop loop(s, kDt);
    test::MotorPlant m(s, tau);
    if (tau != s.response_tau_s) m.gain *= 0.85f;
    float worst = 0.0f, worst_estimate = 0.0f;
    for (int i = 0; i < 3000; ++i) {
      const float before = m.omega;
      const float duty = loop.step(i < 1000 ? 3.0f : 1.0f, true, m.counter());
      if (i > 20) worst_estimate = std::max(worst_estimate, std::fabs(loop.speedRadS() - before));
      m.step(duty, false, kDt);
      if (i > 20) worst = std::max(worst, std::fabs(m.omega - loop.modelSpeed()));
    }
    EXPECT_LT(worst, tau == s.response_tau_s ? 0.02f : 0.65f) << "motor tau " << tau;  // of a 3 rad/s step
    // The frames' speed: the wheel's now, not the window's 10 ms ago (0.15 rad/s off after the step).
    EXPECT_LT(worst_estimate, tau == s.response_tau_s ? 0.03f : 0.15f) << "motor tau " << tau;
    EXPECT_NEAR(m.omega, 1.0f, 0.03f) << "motor tau " << tau;
  }
}

TEST(WheelSpeedLoop, ClampsToTheWheelSpeedLimitAndAnswersAsTheModelNotFaster) {
  const McuSettings s = robotYaml();
  WheelSpeedLoop loop(s, kDt);
  test::MotorPlant m(s);
  run(loop, m, 100.0f, s.response_tau_s);
  EXPECT_FLOAT_EQ(loop.appliedSetpoint(), s.max_wheel_speed_rad_s);
  // One time constant after the step: 63 % of the way, as the plant of mcu_sim's emulator.
  EXPECT_NEAR(m.omega, 0.632f * s.max_wheel_speed_rad_s, 0.1f);
  run(loop, m, 100.0f, 2.0f);
  EXPECT_FLOAT_EQ(loop.appliedSetpoint(), s.max_wheel_speed_rad_s);
  EXPECT_NEAR(m.omega, s.max_wheel_speed_rad_s, 0.1f);
}

TEST(WheelSpeedLoop, AStalledWheelDoesNotWindUpTheIntegral) {
  const McuSettings s = robotYaml();
  WheelSpeedLoop loop(s, kDt);
  test::MotorPlant m(s);
  m.stalled = true;
  run(loop, m, 3.0f, 3.0f);
  EXPECT_FLOAT_EQ(loop.duty(), 1.0f);
  EXPECT_NEAR(loop.speedRadS(), 0.0f, 0.01f) << "held: the frames say so, whatever the model";
  m.stalled = false;
  const float peak = run(loop, m, 3.0f, 2.0f);
  EXPECT_LT(peak, 3.0f * 1.25f) << "a wound-up integral would drive it far past the set-point";
  EXPECT_NEAR(m.omega, 3.0f, 0.06f);
}

TEST(WheelSpeedLoop, DisabledBrakesAndForgets) {
  const McuSettings s = robotYaml();
  WheelSpeedLoop loop(s, kDt);
  test::MotorPlant m(s);
  run(loop, m, 3.0f, 1.0f);
  EXPECT_EQ(loop.step(3.0f, false, m.counter()), 0.0f);
  EXPECT_EQ(loop.appliedSetpoint(), 0.0f);
}

TEST(EncoderTracker, CountsAcrossTheTimersWrapBothWays) {
  EncoderTracker e;
  e.update(65530);
  e.update(4);  // +10 across the wrap
  EXPECT_EQ(e.total(), 10);
  e.update(65526);  // -14
  EXPECT_EQ(e.total(), -4);
}

TEST(Odometry, OneTurnOfBothWheelsAndAQuarterTurnOnTheSpot) {
  const McuSettings s = robotYaml();
  Odometry o(s);
  o.update(0, 0);
  o.update(s.encoder_counts_per_rev, s.encoder_counts_per_rev);
  const double turn_0p1mm = 2 * 3.14159265358979 * s.wheel_radius_m * 1e4;
  EXPECT_NEAR(o.displacement0p1mm()[0], turn_0p1mm, 1.0);
  EXPECT_NEAR(o.displacement0p1mm()[1], turn_0p1mm, 1.0);
  EXPECT_EQ(o.heading0p1mrad(), 0);
  // Right forward, left back, each by track x pi/4 of travel: +pi/2, counter-clockwise.
  const double counts = s.track_m * 3.14159265358979 / 4 / (2 * 3.14159265358979 * s.wheel_radius_m) * s.encoder_counts_per_rev;
  o.update(s.encoder_counts_per_rev - std::llround(counts), s.encoder_counts_per_rev + std::llround(counts));
  EXPECT_NEAR(o.heading0p1mrad(), 15708, 10);
}

TEST(UltrasonicScheduler, FiresInTurnOnePerSlotAndTurnsEchoTimesIntoRanges) {
  const McuSettings s = robotYaml();
  UltrasonicScheduler u(s);
  std::vector<int> fired;
  EchoCapture echo{true, true, 5831};  // 1000 mm there and back at 343 m/s
  for (uint32_t t = 0; t < 4u * s.ultrasonic_slot_ms + 1; ++t)
    if (const int k = u.tick(t, echo); k >= 0) fired.push_back(k);
  EXPECT_EQ(fired, (std::vector<int>{0, 1, 2, 3, 0}));
  for (auto mm : u.rangesMm()) EXPECT_NEAR(mm, 1000, 1);
  EXPECT_FALSE(u.fault());
}

TEST(UltrasonicScheduler, NoEchoBeyondRangeAndASilentSensorIsAFault) {
  McuSettings s = robotYaml();
  UltrasonicScheduler u(s);
  uint32_t t = 0;
  auto slot = [&](EchoCapture e) {  // runs to the end of the next slot with that capture
    for (uint32_t end = t + s.ultrasonic_slot_ms; t < end; ++t) u.tick(t, e);
  };
  u.tick(t++, {});  // fires sensor 0
  slot({true, false, 0});  // still high at the slot's end: nothing in range
  EXPECT_EQ(u.rangesMm()[0], serial::kNoEcho);
  slot({true, true, 30000});  // 5.1 m: beyond max_range_m 4.5
  EXPECT_EQ(u.rangesMm()[1], serial::kNoEcho);
  slot({true, true, 58});  // 1 cm: under min_range_m reads as min
  EXPECT_EQ(u.rangesMm()[2], 20);
  for (int i = 0; i < 4 * s.ultrasonic_missed_limit; ++i) slot({});  // nobody answers
  EXPECT_TRUE(u.fault());
  for (int i = 0; i < 4; ++i) slot({true, true, 5831});
  EXPECT_FALSE(u.fault());
  EXPECT_EQ(u.readings()[0], static_cast<uint32_t>(1 + s.ultrasonic_missed_limit + 1));
}

TEST(ObstacleStop, CutsForwardMotionKeepsTurningAndBackingAndHasHysteresis) {
  const McuSettings s = robotYaml();  // stop under 0.15 m, clear over 0.20 m
  ObstacleStop o(s);
  o.update(1000, 0xFFFF);
  float l = 2.0f, r = 3.0f;
  o.limit(l, r);
  EXPECT_EQ(l, 2.0f);
  o.update(140, 0xFFFF);
  ASSERT_TRUE(o.active());
  l = 2.0f, r = 3.0f;  // forward, turning left
  o.limit(l, r);
  EXPECT_FLOAT_EQ(l, -0.5f);
  EXPECT_FLOAT_EQ(r, 0.5f);  // only the turn is left
  l = -1.0f, r = -1.0f;  // backing away
  o.limit(l, r);
  EXPECT_EQ(l, -1.0f);
  o.update(180, 0xFFFF);
  EXPECT_TRUE(o.active()) << "between stop and clear: still active";
  o.update(210, 250);
  EXPECT_FALSE(o.active());
}

TEST(AnalogInputs, GasTransmittersFourToTwentyMilliampsWithNamurFaults) {
  const McuSettings s = robotYaml();  // CH4: 0-100 %LEL, scale 0.01
  const auto& ch4 = s.gas[0];
  // One ADC count is 16 mA / 2978 counts: 0.034 %LEL, 3.4 frame counts.
  EXPECT_NEAR(gasCount(s, ch4, gasAdcCounts(s, ch4, 0.0f)), 0, 4);
  EXPECT_NEAR(gasCount(s, ch4, gasAdcCounts(s, ch4, 50.0f)), 5000, 5);  // 12 mA: 50 %LEL
  EXPECT_NEAR(gasCount(s, ch4, gasAdcCounts(s, ch4, 12.5f)), 1250, 5);
  const float amps_per_count = kAdcVref / kAdcFullScale / s.gas_shunt_ohm;
  EXPECT_EQ(gasCount(s, ch4, static_cast<uint16_t>(3.5e-3f / amps_per_count)), serial::kGasNoData);   // under 3.6 mA
  EXPECT_EQ(gasCount(s, ch4, static_cast<uint16_t>(21.2e-3f / amps_per_count)), serial::kGasNoData);  // over 21 mA
  EXPECT_EQ(gasCount(s, ch4, 0), serial::kGasNoData);  // a broken loop
  EXPECT_NE(gasCount(s, ch4, static_cast<uint16_t>(3.8e-3f / amps_per_count)), serial::kGasNoData);  // under-range, no fault
}

TEST(AnalogInputs, BatteryMillivoltsAndItsLowFlagWithHysteresis) {
  const McuSettings s = robotYaml();
  EXPECT_NEAR(batteryMv(s, batteryAdcCounts(s, 25200)), 25200, 10);
  BatteryMonitor b(s);
  b.update(22300);
  EXPECT_FALSE(b.low());
  b.update(22100);
  EXPECT_TRUE(b.low());
  b.update(22500);
  EXPECT_TRUE(b.low());
  b.update(22700);
  EXPECT_FALSE(b.low());
}

TEST(Debounced, ABounceShorterThanTheDebounceIsIgnored) {
  Debounced d(10);
  for (int i = 0; i < 9; ++i) EXPECT_FALSE(d.update(true));
  EXPECT_FALSE(d.update(false));  // bounced back: starts again
  for (int i = 0; i < 9; ++i) d.update(true);
  EXPECT_TRUE(d.update(true));
}

TEST(PtzServo, SlewsAtItsLimitToTheSetPointAndHomes) {
  const McuSettings s = robotYaml();  // 120 deg/s
  PtzServo p(s, kDt);
  p.setTarget(7854, -2618, false);  // 45 deg, -15 deg
  for (int i = 0; i < 100; ++i) p.step();
  EXPECT_NEAR(p.anglesRad()[0], s.ptz_slew_rad_s * 0.1f, 1e-3f);  // 12 deg after 0.1 s
  for (int i = 0; i < 1000; ++i) p.step();
  EXPECT_NEAR(p.anglesRad()[0], 0.7854f, 1e-4f);
  EXPECT_NEAR(p.pulsesUs()[0], 1500 + 500, 1);  // 45 deg: 11.11 us/deg
  EXPECT_NEAR(p.pulsesUs()[1], 1500 - 167, 1);
  p.setTarget(1000, 1000, true);
  for (int i = 0; i < 1000; ++i) p.step();
  EXPECT_EQ(p.pulsesUs()[0], 1500);
}

}  // namespace
}  // namespace inspect::firmware
