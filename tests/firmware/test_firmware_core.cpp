// The firmware core as the Pi sees it (docs/firmware.md, docs/serial-protocol.md):
// bytes in and out through shared/serial's codec, its timers on a 1 ms tick,
// two motors and encoders simulated around it.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "firmware/core/firmware_core.hpp"
#include "firmware/host/settings_from_config.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/serial/frame_codec.hpp"
#include "tests/firmware/motor_plant.hpp"
#include "tests/support/paths.hpp"

namespace inspect::firmware {
namespace {

/// The Pi's end of the line, and the robot's motors and sensors around the core.
class FirmwareBench : public ::testing::Test {
 protected:
  FirmwareBench()
      : settings_(settingsFrom(config::loadRobotConfigFile(inspect::test::srcPath("config/robot.yaml")))),
        core_(settings_),
        left_(settings_),
        right_(settings_) {
    for (std::size_t i = 0; i < settings_.gas_channel_count; ++i)
      in_.gas_adc[i] = gasAdcCounts(settings_, settings_.gas[i], settings_.gas[i].range_min);
    in_.battery_adc = batteryAdcCounts(settings_, 25000);
    in_.echo = {true, false, 0};  // every sensor answers: nothing in range
  }

  void send(const serial::Message& m) {
    const auto f = pi_encoder_.encode(m);
    core_.receive(f.span(), now_);
  }
  void sendRaw(const std::vector<uint8_t>& bytes) { core_.receive(bytes, now_); }
  void wheels(float left, float right, bool enable = true) {
    send(serial::WheelCommand{static_cast<int16_t>(std::lround(left * 1000)), static_cast<int16_t>(std::lround(right * 1000)),
                              static_cast<uint8_t>(enable ? serial::WheelCommand::kEnable : 0)});
  }
  /// Runs `ms` ticks; every `command_every_ms` (0: never) the Pi sends the
  /// wheel set-points again and a heartbeat each 100 ms, as robot_client does.
  void run(int ms, int command_every_ms = 10, float left = 0, float right = 0) {
    for (int i = 0; i < ms; ++i) {
      if (command_every_ms > 0 && i % command_every_ms == 0) wheels(left, right);
      if (command_every_ms > 0 && i % 100 == 0) send(serial::Heartbeat{now_});
      in_.encoder = {left_.counter(), right_.counter()};
      out_ = core_.tick(now_, in_);
      left_.step(out_.duty[0], out_.brake, FirmwareCore::kPeriodS);
      right_.step(out_.duty[1], out_.brake, FirmwareCore::kPeriodS);
      std::array<uint8_t, 64> buf{};
      for (std::size_t n; (n = core_.takeTx(buf)) > 0;)
        pi_decoder_.feed(std::span<const uint8_t>(buf.data(), n), [&](const serial::Message& m, uint8_t) {
          if (const auto* f = std::get_if<serial::SensorFrame>(&m)) frames_.push_back({now_, *f});
        });
      ++now_;
    }
  }
  const serial::SensorFrame& last() const { return frames_.back().second; }

  McuSettings settings_;
  FirmwareCore core_;
  test::MotorPlant left_, right_;
  PeripheralInputs in_;
  PeripheralOutputs out_;
  serial::FrameEncoder pi_encoder_;
  serial::FrameDecoder pi_decoder_;
  std::vector<std::pair<uint32_t, serial::SensorFrame>> frames_;
  uint32_t now_ = 1000;
};

TEST_F(FirmwareBench, SensorFramesAtOneHundredHertzWithTheWheelsTheCommandsMove) {
  run(2000, 10, 2.0f, 3.0f);
  EXPECT_EQ(frames_.size(), 200u);
  EXPECT_EQ(pi_decoder_.counters().errors(), 0u);
  EXPECT_EQ(pi_decoder_.counters().seq_gaps, 0u);
  EXPECT_EQ(last().mcu_time_ms, now_ - 10);
  EXPECT_NEAR(last().wheel_speed_mrad_s[0], 2000, 60);
  EXPECT_NEAR(last().wheel_speed_mrad_s[1], 3000, 60);
  EXPECT_GT(last().heading_0p1mrad, 0) << "a faster right wheel turns it left";
  EXPECT_GT(last().wheel_disp_0p1mm[1], last().wheel_disp_0p1mm[0]);
  EXPECT_EQ(last().faults, 0) << last().faults;
  EXPECT_NEAR(last().battery_mv, 25000, 10);
  EXPECT_EQ(core_.counters().wheel_commands, 200u);
}

TEST_F(FirmwareBench, TheWatchdogStopsTheMotorsTwoHundredMsAfterTheLastCommandUntilTheNext) {
  run(1000, 10, 3.0f, 3.0f);
  const uint32_t last_command = now_ - 10;
  run(600, 0);
  int tripped_at = -1;
  for (const auto& [t, f] : frames_)
    if (tripped_at < 0 && (f.faults & serial::kFaultWatchdog)) tripped_at = static_cast<int>(t - last_command);
  EXPECT_GE(tripped_at, 200);
  EXPECT_LE(tripped_at, 210) << "within 200 ms plus one frame period";
  EXPECT_TRUE(out_.brake);
  EXPECT_EQ(core_.setpoints()[0], 0.0f);
  EXPECT_EQ(core_.counters().watchdog_trips, 1u);
  EXPECT_TRUE(last().faults & serial::kFaultHostSilent) << "no heartbeat for 600 ms + the last";
  run(1000, 10, 1.0f, 1.0f);  // the robot's response: five time constants
  EXPECT_FALSE(last().faults & (serial::kFaultWatchdog | serial::kFaultHostSilent));
  EXPECT_NEAR(last().wheel_speed_mrad_s[0], 1000, 100);
}

TEST_F(FirmwareBench, CorruptedAndGarbageBytesAreCountedByCauseAndNeverMoveAMotor) {
  run(100, 10, 0.0f, 0.0f);
  // A wheel command of 4 rad/s with one bit flipped after encoding.
  auto f = pi_encoder_.encode(serial::WheelCommand{4000, 4000, serial::WheelCommand::kEnable});
  std::vector<uint8_t> bytes(f.bytes.begin(), f.bytes.begin() + static_cast<long>(f.size));
  bytes[3] ^= 0x10;
  sendRaw(bytes);
  sendRaw({0x02, 0x20, 0x00});                  // too short
  sendRaw({0x03, 0x55, 0x01, 0x00});            // bad COBS / length
  sendRaw(std::vector<uint8_t>(300, 0x42));     // no delimiter for 300 bytes
  sendRaw({0x00});
  for (int i = 0; i < 20; ++i) {
    in_.encoder = {left_.counter(), right_.counter()};
    out_ = core_.tick(now_++, in_);
    EXPECT_EQ(out_.duty[0], 0.0f);
  }
  const auto& c = core_.counters().rx;
  EXPECT_EQ(c.bad_crc, 1u);
  EXPECT_EQ(c.overflow, 1u);
  EXPECT_GE(c.bad_cobs + c.bad_length, 2u);
  EXPECT_EQ(core_.setpoints()[0], 0.0f);
  EXPECT_EQ(core_.counters().wheel_commands, 10u);
}

TEST_F(FirmwareBench, TheEStopButtonAndTheDriversFaultBrakeWhateverTheCommands) {
  run(500, 10, 2.0f, 2.0f);
  in_.estop_pressed = true;
  run(5, 10, 2.0f, 2.0f);
  EXPECT_FALSE(out_.brake) << "a 5 ms press is contact bounce";
  run(20, 10, 2.0f, 2.0f);
  EXPECT_TRUE(out_.brake);
  EXPECT_TRUE(last().faults & serial::kFaultEStopButton);
  in_.estop_pressed = false;
  run(30, 10, 2.0f, 2.0f);
  EXPECT_FALSE(out_.brake);
  in_.motor_driver_fault = true;
  run(20, 10, 2.0f, 2.0f);
  EXPECT_TRUE(out_.brake);
  EXPECT_TRUE(last().faults & serial::kFaultMotorDriver);
}

TEST_F(FirmwareBench, AWallAheadStopsForwardMotionButNotTheTurnAwayAndRaisesObstacleStop) {
  in_.echo = {true, true, 700};  // 120 mm on every sensor
  run(1000, 10, 2.0f, 2.0f);
  EXPECT_TRUE(last().faults & serial::kFaultObstacleStop);
  EXPECT_NEAR(last().wheel_speed_mrad_s[0], 0, 30);
  EXPECT_NEAR(last().ultrasonic_mm[0], 120, 1);
  run(1000, 10, -1.0f, 1.0f);  // turning on the spot is allowed
  EXPECT_NEAR(last().wheel_speed_mrad_s[1], 1000, 80);
  in_.echo = {true, false, 0};  // the wall is gone
  run(200, 10, 2.0f, 2.0f);
  EXPECT_FALSE(last().faults & serial::kFaultObstacleStop);
}

TEST_F(FirmwareBench, GasLineBatteryAndPtzReachTheFrame) {
  in_.gas_adc[0] = gasAdcCounts(settings_, settings_.gas[0], 25.0f);  // CH4 25 %LEL
  in_.gas_adc[1] = 10;                                                  // H2S loop broken
  in_.grayscale = 0x05;
  in_.battery_adc = batteryAdcCounts(settings_, 22000);
  send(serial::PtzCommand{5236, 0, 0});  // 30 degrees
  run(1000, 10);
  EXPECT_NEAR(last().gas_raw[0], 2500, 3);
  EXPECT_EQ(last().gas_raw[1], 0xFFFF);
  EXPECT_TRUE(last().faults & serial::kFaultGasSensor);
  EXPECT_TRUE(last().faults & serial::kFaultBatteryLow);
  EXPECT_EQ(last().grayscale, 0x05);
  EXPECT_NEAR(out_.servo_us[0], 1500 + 333, 1);
}

TEST_F(FirmwareBench, AnUndrainedUartDropsWholeFramesAndCountsThem) {
  for (int i = 0; i < 100; ++i) {
    in_.encoder = {left_.counter(), right_.counter()};
    core_.tick(now_++, in_);
  }
  EXPECT_EQ(core_.counters().frames_sent, FirmwareCore::kTxBuffer / 46);
  EXPECT_EQ(core_.counters().frames_sent + core_.counters().tx_overruns, 10u);
  std::array<uint8_t, FirmwareCore::kTxBuffer> buf{};
  const std::size_t n = core_.takeTx(buf);
  std::size_t decoded = 0;
  pi_decoder_.feed(std::span<const uint8_t>(buf.data(), n), [&](const serial::Message&, uint8_t) { ++decoded; });
  EXPECT_EQ(decoded, core_.counters().frames_sent);
  EXPECT_EQ(pi_decoder_.counters().errors(), 0u);
}

}  // namespace
}  // namespace inspect::firmware
