// The simulator's end of the HIL link (sim/hil_mcu.hpp) and the link's codec
// (shared/hil): what the firmware's board would read, turned back by the
// firmware core's own conversions; its duty as the motors' targets.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "firmware/core/analog_inputs.hpp"
#include "firmware/host/settings_from_config.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/hil/encoder_model.hpp"
#include "shared/hil/hil_link.hpp"
#include "sim/hil_mcu.hpp"
#include "sim/simulation.hpp"
#include "tests/support/paths.hpp"

namespace inspect::sim {
namespace {

config::RobotConfig robot() { return config::loadRobotConfigFile(test::srcPath("config/robot.yaml")); }

template <class T>
std::vector<T> decodeAll(const std::vector<uint8_t>& bytes) {
  std::vector<T> out;
  hil::HilDecoder d;
  d.feed(bytes, [&](const hil::HilMessage& m, uint8_t) {
    if (const auto* in = std::get_if<T>(&m)) out.push_back(*in);
  });
  EXPECT_EQ(d.errors(), 0u);
  return out;
}
const auto decodeInputs = decodeAll<hil::HilSensors>;

std::vector<uint8_t> frameOf(const hil::HilOutputs& o, uint8_t seq = 0) {
  const auto f = hil::encodeHil(o, seq);
  return {f.bytes.begin(), f.bytes.begin() + static_cast<std::ptrdiff_t>(f.size)};
}

TEST(HilLink, EveryMessageRoundTripsAndCorruptionIsCounted) {
  const hil::HilEncoders enc{{65535, 12}, {-13039, 2000000}, 65000};
  hil::HilSensors in;
  in.echo_count = 7;
  in.echo_flags = hil::HilSensors::kEchoRose | hil::HilSensors::kEchoFell;
  in.echo_width_us = 5831;
  in.gas_adc = {1, 2, 3, 4095};
  in.battery_adc = 2800;
  in.grayscale = 0xA5;
  in.switches = hil::HilSensors::kEStopPressed;
  hil::HilOutputs out;
  out.mcu_time_ms = 123456789;
  out.duty_1e4 = {-10000, 2500};
  out.flags = hil::HilOutputs::kBrake;
  out.trigger_sensor = 3;
  out.trigger_count = 255;
  out.servo_us = {500, 2500};
  out.tick_late_us = 65535;
  out.input_seq = 77;
  out.setpoint_mrad_s = {-1234, 5000};
  out.ptz_target_0p1mrad = {-31416, 7854};
  std::vector<uint8_t> wire;
  for (const hil::HilMessage& m : {hil::HilMessage(enc), hil::HilMessage(in), hil::HilMessage(out)}) {
    const auto f = hil::encodeHil(m, 9);
    wire.insert(wire.end(), f.bytes.begin(), f.bytes.begin() + static_cast<std::ptrdiff_t>(f.size));
  }
  std::vector<hil::HilMessage> got;
  hil::HilDecoder d;
  d.feed(wire, [&](const hil::HilMessage& m, uint8_t seq) {
    EXPECT_EQ(seq, 9);
    got.push_back(m);
  });
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(std::get<hil::HilEncoders>(got[0]), enc);
  EXPECT_EQ(std::get<hil::HilSensors>(got[1]), in);
  EXPECT_EQ(std::get<hil::HilOutputs>(got[2]), out);
  // One bit flipped in a frame: dropped and counted, the next one taken.
  auto bad = frameOf(out);
  bad[4] ^= 0x01;
  bad.insert(bad.end(), wire.begin(), wire.end());
  got.clear();
  d.feed(bad, [&](const hil::HilMessage& m, uint8_t) { got.push_back(m); });
  EXPECT_EQ(d.errors(), 1u);
  EXPECT_EQ(got.size(), 3u);
}

TEST(HilLink, TheBoardReadsItsEncodersAtTheTicksInstantFromASampleAndItsRate) {
  // 16384 counts per turn, 0.154 duty per rad/s: 16931 counts/s per unit of duty; tau 0.2 s.
  const float per_duty = 16384.0f / (6.28318530718f * 0.154f);
  hil::HilEncoderModel m(0.154f, 0.2f, 16384);
  EXPECT_EQ(m.countersAt(1000), (std::array<uint16_t, 2>{0, 0}));  // before any sample: at rest
  m.take({{65530, 100}, {13039, -2000}, 65534});  // board_ms wraps too
  // Driven at the duties that hold those rates: the sample's rate carries on.
  m.drive({13039.0f / per_duty, -2000.0f / per_duty});
  EXPECT_EQ(m.countersAt(65534), (std::array<uint16_t, 2>{65530, 100}));
  const auto at6 = m.countersAt(65536 + 4);  // 6 ms later: 78.2 and -12 counts
  EXPECT_EQ(at6[0], static_cast<uint16_t>(65530 + 78));
  EXPECT_EQ(at6[1], 100 - 12);
  // A sample newer than the tick (a late tick catching up): back along the rate.
  m.take({{65530, 100}, {13039, -2000}, 65534});
  EXPECT_EQ(m.countersAt(65530)[0], 65530 - 52);
  // A link that stopped: no further than kMaxExtrapolationMs.
  m.take({{65530, 100}, {13039, -2000}, 65534});
  EXPECT_EQ(m.countersAt(65534 + 1000)[1], static_cast<uint16_t>(100 - 2 * hil::HilEncoderModel::kMaxExtrapolationMs));
}

TEST(HilLink, BetweenSamplesTheCountsFollowTheDutyTheBoardDrivesAsTheSimulatedMotorDoes) {
  // A step from rest and then no sample for 60 ms (a stalled pty): the counts
  // are the motor's first order toward the new duty, within a count, not a
  // wheel frozen at the sample's zero rate.
  const float per_duty = 16384.0f / (6.28318530718f * 0.154f);
  hil::HilEncoderModel m(0.154f, 0.2f, 16384);
  m.take({{1000, 1000}, {0, 0}, 500});
  const float duty = 2.0f * 0.154f;  // 2 rad/s
  m.drive({duty, -duty});
  std::array<uint16_t, 2> c{};
  for (uint32_t t = 501; t <= 560; ++t) c = m.countersAt(t);  // one read per 1 ms tick
  const double target = duty * per_duty, t_s = 0.060, tau = 0.2;
  const double expect = target * t_s - target * tau * (1.0 - std::exp(-t_s / tau));  // 35.3 counts
  EXPECT_NEAR(static_cast<int16_t>(c[0] - 1000), expect, 1.0);
  EXPECT_NEAR(static_cast<int16_t>(c[1] - 1000), -expect, 1.0);
  // The next sample wins over the model.
  m.take({{1100, 900}, {3000, -3000}, 561});
  EXPECT_EQ(m.countersAt(561), (std::array<uint16_t, 2>{1100, 900}));
  // Braked: the motor runs down toward 0.
  m.drive({0.0f, 0.0f});
  const auto later = m.countersAt(571);
  EXPECT_LT(static_cast<int16_t>(later[0] - 1100), 30);  // 3000 counts/s for 10 ms would be 30
  EXPECT_GT(static_cast<int16_t>(later[0] - 1100), 25);
}

TEST(HilMcu, EncoderSamplesAreStampedWithTheBoardsClockFromItsLeastDelayedReport) {
  const auto r = robot();
  HilMcu mcu(r, nullptr);
  hil::HilOutputs o;
  o.mcu_time_ms = 50000;  // the board is 45000 ms ahead of the simulation, plus each report's delay
  mcu.receive(frameOf(o, 0), 5003);
  EXPECT_EQ(mcu.boardClockOffsetMs(), 44997);
  o.mcu_time_ms = 50010;
  mcu.receive(frameOf(o, 1), 5010);  // no delay: the better estimate
  EXPECT_EQ(mcu.boardClockOffsetMs(), 45000);
  o.mcu_time_ms = 50020;
  mcu.receive(frameOf(o, 2), 5028);  // a late one changes nothing
  EXPECT_EQ(mcu.boardClockOffsetMs(), 45000);
  std::vector<uint8_t> tx;
  mcu.sendEncoders(PlantState{}, 5030, tx);
  const auto enc = decodeAll<hil::HilEncoders>(tx);
  ASSERT_EQ(enc.size(), 1u);
  EXPECT_EQ(enc[0].board_ms, static_cast<uint16_t>(50030));
  // Reports 1-2 ms later than the best change nothing.
  for (uint64_t t = 5040; t < 5040 + 3 * HilMcu::kClockWindow_ms; t += 10) {
    o.mcu_time_ms = static_cast<uint32_t>(t + 45000 - 1 - (t / 10) % 2);
    mcu.receive(frameOf(o, static_cast<uint8_t>(t / 10)), t);
  }
  EXPECT_EQ(mcu.boardClockOffsetMs(), 45000);
  // The board's clock 100 ms back from now on (it restarted its schedule
  // after a stall): followed within two windows.
  const uint64_t from = 5040 + 3 * HilMcu::kClockWindow_ms;
  for (uint64_t t = from; t < from + 2 * HilMcu::kClockWindow_ms + 10; t += 10) {
    o.mcu_time_ms = static_cast<uint32_t>(t + 44900);
    mcu.receive(frameOf(o, static_cast<uint8_t>(t / 10)), t);
  }
  EXPECT_EQ(mcu.boardClockOffsetMs(), 44900);
}

TEST(HilMcu, TheFirmwaresDutyDrivesTheMotorsAndTheBrakeStopsThem) {
  const auto r = robot();
  const auto s = firmware::settingsFrom(r);
  HilMcu mcu(r, nullptr);
  EXPECT_EQ(mcu.motorTargets().left_rad_s, 0.0);  // nothing heard: at rest
  hil::HilOutputs o;
  o.duty_1e4 = {5000, -2500};
  mcu.receive(frameOf(o), 0);
  EXPECT_NEAR(mcu.motorTargets().left_rad_s, 0.5 / s.speed_ff, 1e-6);
  EXPECT_NEAR(mcu.motorTargets().right_rad_s, -0.25 / s.speed_ff, 1e-6);
  o.flags = hil::HilOutputs::kBrake;
  mcu.receive(frameOf(o, 1), 2);
  EXPECT_EQ(mcu.motorTargets().left_rad_s, 0.0);
  EXPECT_EQ(mcu.framesReceived(), 2u);
}

TEST(HilMcu, WhatItSendsReadsBackThroughTheFirmwaresConversions) {
  const auto r = robot();
  const auto s = firmware::settingsFrom(r);
  HilMcu mcu(r, nullptr);
  PlantState truth;
  const double per_count = 2.0 * std::numbers::pi * r.geometry.wheel_radius_m / s.encoder_counts_per_rev;
  truth.wheel_travel_left_m = 1000.5 * per_count;
  truth.wheel_travel_right_m = -3.5 * per_count;
  mcu.receive(frameOf(hil::HilOutputs{}), 0);  // the board speaks: the simulator sends
  std::array<uint16_t, serial::kGasChannels> gas{};
  gas[0] = 250;                  // a reading
  gas[1] = serial::kGasNoData;  // a failed sensor
  std::vector<uint8_t> tx;
  truth.wheel = {2.0, -1.0};
  mcu.sendEncoders(truth, 0, tx);
  const auto enc = decodeAll<hil::HilEncoders>(tx);
  ASSERT_EQ(enc.size(), 1u);
  EXPECT_EQ(enc[0].counter[0], 1000);
  EXPECT_EQ(enc[0].counter[1], static_cast<uint16_t>(-4));
  EXPECT_EQ(enc[0].rate_counts_s[0], std::lround(2.0 * s.encoder_counts_per_rev / (2.0 * std::numbers::pi)));
  EXPECT_EQ(enc[0].rate_counts_s[1], std::lround(-1.0 * s.encoder_counts_per_rev / (2.0 * std::numbers::pi)));
  tx.clear();
  mcu.sendSensors(60000, 0x18, gas, tx);
  const auto in = decodeInputs(tx);
  ASSERT_EQ(in.size(), 1u);
  EXPECT_EQ(in[0].grayscale, 0x18);
  ASSERT_GE(s.gas_channel_count, 2);
  EXPECT_NEAR(firmware::gasCount(s, s.gas[0], in[0].gas_adc[0]), 250, 2);  // within the ADC's resolution
  EXPECT_EQ(firmware::gasCount(s, s.gas[1], in[0].gas_adc[1]), serial::kGasNoData);
  // The emulated MCU's battery after a minute: 25200 - 0.5 x 60 mV.
  EXPECT_NEAR(firmware::batteryMv(s, in[0].battery_adc), 25170, 15);
  EXPECT_EQ(in[0].echo_flags, hil::HilSensors::kEchoRose);  // no ping yet: nothing in range
}

TEST(HilMcu, APingIsAnsweredOnceWithItsEcho) {
  const auto r = robot();
  HilMcu mcu(r, nullptr);
  hil::HilOutputs o;
  mcu.receive(frameOf(o), 0);
  EXPECT_EQ(mcu.pendingPing(), -1);
  o.trigger_sensor = 2;
  o.trigger_count = 1;
  mcu.receive(frameOf(o, 1), 2);
  EXPECT_EQ(mcu.pendingPing(), 2);
  mcu.answerPing(1000);  // 1 m: 5831 us out and back at 343 m/s
  EXPECT_EQ(mcu.pendingPing(), -1);
  std::vector<uint8_t> tx;
  mcu.sendSensors(4, 0, {}, tx);
  auto in = decodeInputs(tx);
  ASSERT_EQ(in.size(), 1u);
  EXPECT_EQ(in[0].echo_count, 1);
  EXPECT_EQ(in[0].echo_flags, hil::HilSensors::kEchoRose | hil::HilSensors::kEchoFell);
  EXPECT_NEAR(in[0].echo_width_us, 5831, 1);
  o.trigger_count = 2;
  mcu.receive(frameOf(o, 2), 6);
  mcu.answerPing(serial::kNoEcho);
  tx.clear();
  mcu.sendSensors(8, 0, {}, tx);
  in = decodeInputs(tx);
  EXPECT_EQ(in[0].echo_count, 2);
  EXPECT_EQ(in[0].echo_flags, hil::HilSensors::kEchoRose);
}

TEST(HilMcu, NothingBeforeTheBoardSpeaksAndAtMostTwoFramesInFlight) {
  const auto r = robot();
  HilMcu mcu(r, nullptr);
  std::vector<uint8_t> tx;
  mcu.sendEncoders(PlantState{}, 0, tx);
  EXPECT_TRUE(tx.empty());  // the board holds the world still until it speaks
  hil::HilOutputs o;
  o.input_seq = 200;
  mcu.receive(frameOf(o), 0);
  for (int i = 0; i < 10; ++i) mcu.sendEncoders(PlantState{}, 0, tx);
  EXPECT_EQ(decodeAll<hil::HilEncoders>(tx).size(), HilMcu::kMaxInFlight);
  EXPECT_EQ(mcu.framesHeldBack(), 1u + 10u - HilMcu::kMaxInFlight);
  EXPECT_FALSE(mcu.boardTookInputs());
  o.input_seq = 200 + HilMcu::kMaxInFlight;  // the board took them all
  mcu.receive(frameOf(o, 1), 2);
  EXPECT_TRUE(mcu.boardTookInputs());
  tx.clear();
  mcu.sendEncoders(PlantState{}, 0, tx);
  EXPECT_EQ(decodeAll<hil::HilEncoders>(tx).size(), 1u);
}

TEST(HilMcu, TheSimulationInTheLoopSendsEncodersEvery10msSensorsEvery20msAndFollowsTheDuty) {
  const auto r = robot();
  Simulation sim(r, loadWorldFile(test::srcPath("config/worlds/empty.yaml")), 1);
  sim.useHilFirmware(r);
  EXPECT_EQ(sim.outputPeriodMs(), HilMcu::kPollPeriod_ms);
  // A board that takes every frame at once and answers every 2 ms.
  hil::HilOutputs o;
  o.duty_1e4 = {3000, 3000};
  hil::HilDecoder board;
  std::size_t encoders = 0, sensors = 0;
  std::vector<uint8_t> tx;
  for (uint64_t t = 0; t < 1000; t += 2) {
    sim.receive(frameOf(o, static_cast<uint8_t>(t / 2)));
    sim.advanceTo(t + 2);
    sim.takeTx(tx);
    board.feed(tx, [&](const hil::HilMessage& m, uint8_t seq) {
      o.input_seq = seq;
      encoders += std::holds_alternative<hil::HilEncoders>(m);
      sensors += std::holds_alternative<hil::HilSensors>(m);
    });
  }
  EXPECT_EQ(board.errors(), 0u);
  EXPECT_EQ(encoders, 1000u / HilMcu::kInputPeriod_ms);
  EXPECT_EQ(sensors, 50u);
  // 0.3 duty: toward 0.3 / speed_ff = 1.95 rad/s; after 1 s (5 time constants) nearly there.
  const double want = 0.3 / firmware::settingsFrom(r).speed_ff;
  EXPECT_NEAR(sim.state().wheel.left_rad_s, want, 0.05 * want);
  EXPECT_GT(sim.state().pose.x_m, 0.2);
}

}  // namespace
}  // namespace inspect::sim
