// MCU emulation: set-points, the 200 ms watchdog, heartbeat monitoring,
// corrupt input, and the 100 Hz sensor frames.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "shared/config/robot_config.hpp"
#include "shared/serial/frame_codec.hpp"
#include "sim/mcu_emulator.hpp"
#include "sim/simulation.hpp"
#include "tests/sim/sensor_frames.hpp"

using namespace inspect;
using namespace inspect::sim;

namespace {

struct Recorder : SimObserver {
  struct Event {
    double t_s;
    std::string name, detail;
  };
  std::vector<Event> events;
  std::vector<TruthSample> samples;
  int commands = 0;
  void onSample(const TruthSample& s) override { samples.push_back(s); }
  void onCommand(double, uint8_t, const serial::WheelCommand&) override { ++commands; }
  void onEvent(double t, std::string_view e, std::string_view d) override {
    events.push_back({t, std::string(e), std::string(d)});
  }
  int count(const std::string& name) const {
    int n = 0;
    for (const auto& e : events) n += e.name == name;
    return n;
  }
};

std::vector<uint8_t> frameBytes(serial::FrameEncoder& enc, const serial::Message& m) {
  const auto f = enc.encode(m);
  return {f.bytes.begin(), f.bytes.begin() + static_cast<std::ptrdiff_t>(f.size)};
}

World emptyWorld() { return World{}; }

}  // namespace

TEST(McuEmulator, CommandsEvery10msKeepSetpointsThenWatchdogZeroesAt200ms) {
  Recorder rec;
  McuEmulator mcu(config::RobotConfig{}, 1, &rec);
  serial::FrameEncoder enc;
  uint64_t last_cmd_ms = 0;
  for (uint64_t t = 0; t < 2000; ++t) {
    if (t % 10 == 0 && t <= 1000) {
      const int16_t l = static_cast<int16_t>(1000 + t);  // a changing set-point
      mcu.receive(frameBytes(enc, serial::WheelCommand{l, -1500, serial::WheelCommand::kEnable}), t);
      last_cmd_ms = t;
      EXPECT_DOUBLE_EQ(mcu.setpoints().left_rad_s, l / 1000.0) << t;
      EXPECT_DOUBLE_EQ(mcu.setpoints().right_rad_s, -1.5) << t;
    }
    mcu.tick(t);
    const bool should_run = t >= 200 && t < last_cmd_ms + McuEmulator::kWatchdog_ms;
    if (t < 1000) {
      EXPECT_FALSE(mcu.watchdogTripped()) << t;
    }
    if (should_run) {
      EXPECT_NE(mcu.setpoints().left_rad_s, 0.0) << t;
    }
    if (t >= last_cmd_ms + McuEmulator::kWatchdog_ms) {
      EXPECT_TRUE(mcu.watchdogTripped()) << t;
      EXPECT_EQ(mcu.setpoints().left_rad_s, 0.0) << t;
      EXPECT_TRUE(mcu.faults() & serial::kFaultWatchdog);
    }
  }
  EXPECT_EQ(rec.commands, 101);
  // Boot trip at 200 ms is impossible here (first command at 0); exactly one trip after the last command.
  ASSERT_EQ(rec.count("watchdog_trip"), 1);
  const auto trip = *std::find_if(rec.events.begin(), rec.events.end(),
                                  [](const auto& e) { return e.name == "watchdog_trip"; });
  EXPECT_NEAR(trip.t_s, 1.2, 0.0011);
  EXPECT_EQ(trip.detail, "200");
}

TEST(McuEmulator, WatchdogTripsAfterBootAndClearsOnNextCommand) {
  Recorder rec;
  McuEmulator mcu(config::RobotConfig{}, 1, &rec);
  serial::FrameEncoder enc;
  for (uint64_t t = 0; t < 300; ++t) mcu.tick(t);
  EXPECT_TRUE(mcu.watchdogTripped());
  EXPECT_EQ(rec.count("watchdog_trip"), 1);
  mcu.receive(frameBytes(enc, serial::WheelCommand{2000, 2000, serial::WheelCommand::kEnable}), 300);
  EXPECT_FALSE(mcu.watchdogTripped());
  EXPECT_EQ(rec.count("watchdog_clear"), 1);
  EXPECT_FALSE(mcu.faults() & serial::kFaultWatchdog);
  EXPECT_DOUBLE_EQ(mcu.setpoints().left_rad_s, 2.0);
}

TEST(McuEmulator, EnableBitAndSpeedLimit) {
  McuEmulator mcu(config::RobotConfig{}, 1);
  serial::FrameEncoder enc;
  mcu.receive(frameBytes(enc, serial::WheelCommand{30000, -30000, serial::WheelCommand::kEnable}), 0);
  EXPECT_DOUBLE_EQ(mcu.setpoints().left_rad_s, 5.0);  // limits.max_wheel_speed_rad_s
  EXPECT_DOUBLE_EQ(mcu.setpoints().right_rad_s, -5.0);
  mcu.receive(frameBytes(enc, serial::WheelCommand{3000, 3000, 0}), 1);
  EXPECT_DOUBLE_EQ(mcu.setpoints().left_rad_s, 0.0);
  EXPECT_DOUBLE_EQ(mcu.setpoints().right_rad_s, 0.0);
  EXPECT_FALSE(mcu.watchdogTripped());  // a disabled command is still a valid command
}

TEST(McuEmulator, CorruptBytesNeverChangeSetpoints) {
  McuEmulator mcu(config::RobotConfig{}, 1);
  serial::FrameEncoder enc;
  mcu.receive(frameBytes(enc, serial::WheelCommand{1234, -567, serial::WheelCommand::kEnable}), 0);
  const auto before = mcu.setpoints();
  std::mt19937 rng(5);
  uint64_t t = 1;
  // Every single-bit flip of a valid command with a different set-point.
  const auto good = frameBytes(enc, serial::WheelCommand{-4000, 4000, serial::WheelCommand::kEnable});
  for (std::size_t i = 0; i + 1 < good.size(); ++i) {
    for (int bit = 0; bit < 8; ++bit) {
      auto bad = good;
      bad[i] ^= static_cast<uint8_t>(1u << bit);
      mcu.receive(bad, t);
      mcu.receive(std::vector<uint8_t>{0}, t);  // resynchronise if the flip made a 0x00 vanish
      mcu.tick(t);
      ASSERT_EQ(mcu.setpoints().left_rad_s, before.left_rad_s) << "byte " << i << " bit " << bit;
      ASSERT_EQ(mcu.setpoints().right_rad_s, before.right_rad_s);
      t = std::min<uint64_t>(t + 1, 150);  // stay inside the watchdog window
    }
  }
  // Random garbage, truncated frames.
  for (int k = 0; k < 2000; ++k) {
    std::vector<uint8_t> junk(1 + rng() % 40);
    for (auto& b : junk) b = static_cast<uint8_t>(rng());
    if (k % 3 == 0) junk.assign(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(1 + rng() % (good.size() - 2)));
    junk.push_back(0);
    mcu.receive(junk, 150);
    ASSERT_EQ(mcu.setpoints().left_rad_s, before.left_rad_s) << "garbage " << k;
  }
  EXPECT_GT(mcu.rxCounters().errors(), 100u);
  EXPECT_EQ(mcu.wheelCommandsApplied(), 1u);
  // A valid frame after all that still works.
  mcu.receive(good, 150);
  EXPECT_DOUBLE_EQ(mcu.setpoints().left_rad_s, -4.0);
}

TEST(McuEmulator, HeartbeatMonitor) {
  Recorder rec;
  McuEmulator mcu(config::RobotConfig{}, 1, &rec);
  serial::FrameEncoder enc;
  for (uint64_t t = 0; t < 1000; ++t) {
    if (t % 100 == 0) mcu.receive(frameBytes(enc, serial::Heartbeat{static_cast<uint32_t>(t)}), t);
    mcu.tick(t);
    ASSERT_FALSE(mcu.faults() & serial::kFaultHostSilent) << t;
  }
  for (uint64_t t = 1000; t < 1400; ++t) mcu.tick(t);
  EXPECT_FALSE(mcu.faults() & serial::kFaultHostSilent);
  mcu.tick(1400);  // 500 ms after the heartbeat at 900
  EXPECT_TRUE(mcu.faults() & serial::kFaultHostSilent);
  EXPECT_EQ(rec.count("host_silent"), 1);
  mcu.receive(frameBytes(enc, serial::Heartbeat{1401}), 1401);
  EXPECT_FALSE(mcu.faults() & serial::kFaultHostSilent);
}

TEST(McuEmulator, PtzIsStoredAndLogged) {
  Recorder rec;
  McuEmulator mcu(config::RobotConfig{}, 1, &rec);
  serial::FrameEncoder enc;
  mcu.receive(frameBytes(enc, serial::PtzCommand{1000, -200, 0}), 5);
  EXPECT_EQ(mcu.ptz().pan_0p1mrad, 1000);
  EXPECT_EQ(mcu.ptz().tilt_0p1mrad, -200);
  mcu.receive(frameBytes(enc, serial::PtzCommand{1000, -200, 1}), 6);  // home
  EXPECT_EQ(mcu.ptz().pan_0p1mrad, 0);
  ASSERT_EQ(rec.count("ptz"), 2);
  EXPECT_NE(rec.events[0].detail.find("pan_0p1mrad=1000"), std::string::npos);
}

TEST(Simulation, HundredHzFramesWithConsistentContents) {
  Recorder rec;
  const config::RobotConfig robot;
  Simulation sim(robot, emptyWorld(), 3, &rec);
  serial::FrameEncoder enc;
  std::vector<uint8_t> all, tx;
  uint8_t last_seq = 0;
  for (int i = 0; i < 100; ++i) {  // 1 s of commands at 0.5 m/s straight ahead
    const auto f = enc.encode(serial::WheelCommand{2500, 2500, serial::WheelCommand::kEnable});
    last_seq = f.seq;
    sim.receive(f.span());
    sim.advanceTo(sim.timeMs() + 10);
    sim.takeTx(tx);
    all.insert(all.end(), tx.begin(), tx.end());
  }
  const auto frames = inspect::test::decodeSensorFrames(all);
  ASSERT_EQ(frames.size(), 100u);
  EXPECT_EQ(rec.samples.size(), 100u);
  for (std::size_t i = 0; i < frames.size(); ++i) EXPECT_EQ(frames[i].mcu_time_ms, 10 * i);
  const auto& last = frames.back();
  EXPECT_EQ(last.cmd_seq_echo, last_seq);  // the command received at 990 ms is in force for the 990 ms frame
  EXPECT_NEAR(last.wheel_speed_mrad_s[0], 2500, 2500 * 0.01 + 11);   // settled, +-0.002 m/s noise = 10 mrad/s
  EXPECT_NEAR(last.wheel_disp_0p1mm[0] / 1e4, sim.state().wheel_travel_left_m, 0.01);
  EXPECT_NEAR(last.heading_0p1mrad, 0, 21);
  EXPECT_EQ(last.ultrasonic_mm[0], serial::kNoEcho);
  EXPECT_EQ(last.battery_mv, 25200);
  EXPECT_EQ(last.faults & serial::kFaultWatchdog, 0);
  EXPECT_TRUE(last.faults & serial::kFaultHostSilent);  // no heartbeats were sent
  EXPECT_NEAR(sim.state().pose.x_m, 0.5 * (1.0 - robot.motor.time_constant_s), 0.01);
}

TEST(Simulation, WatchdogLatencyInSimTime) {
  Recorder rec;
  Simulation sim(config::RobotConfig{}, emptyWorld(), 1, &rec);
  serial::FrameEncoder enc;
  for (int i = 0; i < 50; ++i) {
    sim.receive(enc.encode(serial::WheelCommand{3000, 3000, serial::WheelCommand::kEnable}).span());
    sim.advanceTo(sim.timeMs() + 10);
  }
  const uint64_t last_cmd_ms = sim.timeMs() - 10;
  while (sim.mcu().setpoints().left_rad_s != 0.0 && sim.timeMs() < 2000) sim.step();
  // The set-point is zero for the step that starts at last + 200 ms.
  EXPECT_NEAR(static_cast<double>(sim.timeMs() - 1 - last_cmd_ms), 200.0, 1.0);
  ASSERT_EQ(rec.count("watchdog_trip"), 1);
  EXPECT_EQ(rec.events.back().detail, "200");
}

TEST(McuEmulator, DisplacementWrapsLikeInt32) {
  McuEmulator mcu(config::RobotConfig{}, 1);
  McuInputs in;
  in.truth.wheel_travel_left_m = 214748.3647 + 0.0001;  // one tick past INT32_MAX
  in.truth.wheel_travel_right_m = -1.0;
  std::vector<uint8_t> tx;
  const auto f = mcu.sendSensorFrame(0, in, tx);
  EXPECT_EQ(f.wheel_disp_0p1mm[0], INT32_MIN);
  EXPECT_EQ(f.wheel_disp_0p1mm[1], -10000);
}
