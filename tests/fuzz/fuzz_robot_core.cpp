// Fuzzes robot_client's decision core (RobotCore) through the paths bytes
// reach it by in RobotApp, without sockets or a serial device:
// - the server link: delimited frames (shared/net/delimited_codec) fed in
//   arbitrary chunks, parsed as Envelope, heartbeats and commands handed to
//   the core as RobotApp::onServerMessage does (teleop, stop, e-stop, resume,
//   track, go_to, wheel tests, gains pushes with .fis text, ...);
// - the MCU: serial bytes through the real FrameDecoder, sensor frames into
//   onSensorFrame (with people tracking on, as with config/behavior.yaml);
// - the timer, link and serial state changes.
// The robot's own configs (config/*.yaml, config/fuzzy/*.fis) are loaded once;
// the gas reaction (stop, retreat, continue) follows the input's size % 3.
//
// Input: records (fuzz_records.hpp); tag % 5:
//   0 link bytes; 1 raw serial bytes; 2 a sensor-frame payload (40 bytes,
//   zero-padded) framed with a valid CRC and sent (tag >> 5) + 1 times, 10 ms
//   apart; 3 timer, body[0] ms later; 4 body[0] bits: link up/down, serial
//   open/closed, and (bit 2) a camera picture's people for the tracker
//   (onCameraLook): body[1] % 9 people, 4 bytes each (bearing, range; 0x7fff
//   a NaN, negative ranges for feet out of view). Nothing arrives on a link
//   that is down or a closed serial device.
// Invariants: an Ack answers the command's id; while e-stop or failsafe is
// latched every wheel command is zero; telemetry always serialises and
// parses back.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include <google/protobuf/stubs/logging.h>

#include "inspect_robot/v1/link.pb.h"
#include "robot_client/client_config.hpp"
#include "shared/robot/robot_core.hpp"
#include "shared/world/robot_map.hpp"
#include "shared/behavior/human_awareness.hpp"
#include "shared/behavior/speed_strategy.hpp"
#include "shared/config/control_config.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/net/delimited_codec.hpp"
#include "shared/serial/cobs.hpp"
#include "shared/serial/crc16.hpp"
#include "shared/serial/frame_codec.hpp"
#include "shared/util/log.hpp"
#include "shared/world/world.hpp"
#include "tests/fuzz/fuzz_records.hpp"
#include "tests/support/paths.hpp"

using namespace inspect;

namespace {

struct Setup {
  client::ClientConfig client;
  config::RobotConfig robot;
  config::ControlConfig control;
  std::shared_ptr<control::FuzzyGainScheduler> scheduler;
  behavior::AwarenessConfig awareness;
  std::unique_ptr<behavior::SpeedStrategy> strategy;
  std::vector<geometry::Segment> map;
};
Setup* g_setup = nullptr;

bool latched(const robot::RobotCore& core) { return core.mode() == v1::ESTOP || core.mode() == v1::FAILSAFE; }

void checkWheels(const robot::RobotCore& core, const serial::WheelCommand& c) {
  if (latched(core)) FUZZ_CHECK(c.left_mrad_s == 0 && c.right_mrad_s == 0);
}

struct Robot {
  robot::RobotCore core;
  net::DelimitedDecoder link{net::kDefaultMaxFrame};
  serial::FrameDecoder serial;
  double t = 0.0;
  uint8_t seq = 0;
  bool link_up = true;
  bool serial_open = true;

  Robot(const Setup& s, const robot::SafetyParams& safety) : core(s.robot, safety, s.control, s.scheduler) {
    auto acfg = s.awareness;
    acfg.robot_radius_m = s.robot.geometry.body_radius_m;
    core.setAwareness(std::make_unique<behavior::HumanAwareness>(s.robot.ultrasonic, acfg, *s.strategy, s.map));
    core.onSerialState(true, t);
    core.onLinkUp(t);
    FUZZ_CHECK(core.gasChannels().size() == s.robot.gas.channels.size());  // announced in Hello
  }

  void onSerialBytes(std::span<const uint8_t> bytes) {
    serial.feed(bytes, [&](const serial::Message& m, uint8_t) {
      t += 0.01;
      if (const auto* f = std::get_if<serial::SensorFrame>(&m)) checkWheels(core, core.onSensorFrame(*f, t));
    });
  }

  void onLinkBytes(std::span<const uint8_t> bytes) {
    link.append(bytes);
    for (;;) {
      std::span<const uint8_t> frame;
      const auto st = link.next(frame);
      if (st == net::DelimitedDecoder::Status::kNeedMore) return;
      if (st == net::DelimitedDecoder::Status::kInvalid) {
        // ServerLink drops the connection and reconnects.
        core.onLinkDown(t, "framing error: " + link.error());
        checkWheels(core, core.commandNow());
        link = net::DelimitedDecoder{net::kDefaultMaxFrame};
        core.onLinkUp(t);
        return;
      }
      v1::Envelope env;
      if (!net::DelimitedDecoder::parse(frame, env)) continue;  // ServerLink logs and skips it
      if (env.body_case() == v1::Envelope::kHeartbeat) {
        core.onLinkActivity(t);
      } else if (env.body_case() == v1::Envelope::kCommand) {
        const auto& cmd = env.command();
        if (cmd.has_video() || cmd.has_ptz()) continue;  // the video sender's and the PTZ's, not the core's
        const v1::Ack ack = core.onCommand(cmd, t);
        FUZZ_CHECK(ack.command_id() == cmd.id());
        FUZZ_CHECK(ack.status() != v1::Ack::REJECTED || !ack.reason().empty());
        if (core.mode() != v1::TELEOP && serial_open) checkWheels(core, core.commandNow());
      }
    }
  }

  void drain() {
    (void)core.takeEvents();
    (void)core.takeAcks();
    (void)core.takePtz();
    core.setSerialCounters(serial.counters(), 0, 0);
    v1::Envelope env;
    core.fillTelemetry(*env.mutable_telemetry(), t);
    std::string wire;
    FUZZ_CHECK(net::appendDelimited(env, wire));
    net::DelimitedDecoder d;
    d.append(wire.data(), wire.size());
    std::span<const uint8_t> frame;
    FUZZ_CHECK(d.next(frame) == net::DelimitedDecoder::Status::kFrame);
    v1::Envelope back;
    FUZZ_CHECK(net::DelimitedDecoder::parse(frame, back));
  }
};

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  log::setLevel(log::Level::kError);
  google::protobuf::SetLogHandler([](google::protobuf::LogLevel, const char*, int, const std::string&) {});
  const std::string dir = inspect::test::srcPath("config/");
  auto* s = new Setup;
  s->client = client::loadClientConfigFile(dir + "client.yaml");
  s->robot = config::loadRobotConfigFile(dir + "robot.yaml");
  s->control = config::loadControlConfigFile(dir + "control.yaml");
  // Direct fuzzy inference instead of the lookup surface: compiling a surface
  // for every pushed .fis would cost seconds per input under the sanitizers
  // (fuzz_fis covers the surfaces).
  s->control.use_lookup = false;
  config::applyRobot(s->control, s->robot);
  s->scheduler = config::loadScheduler(s->control);
  s->awareness = behavior::loadAwarenessConfigFile(dir + "behavior.yaml");
  s->strategy = std::make_unique<behavior::SpeedStrategy>(
      behavior::loadSpeedStrategy(s->awareness.speed_fis, s->awareness.speed));
  s->map = world::mapFromWorld(world::loadWorldFile(dir + "worlds/gas_lab.yaml"));
  g_setup = s;
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  // The three reactions to a gas HIGH alarm on a route (client.yaml safety.gas_reaction).
  robot::SafetyParams safety = g_setup->client.safety;
  static constexpr robot::GasReaction kReactions[] = {robot::GasReaction::kStop, robot::GasReaction::kRetreat,
                                                      robot::GasReaction::kContinue};
  safety.gas_reaction = kReactions[size % 3];
  Robot r(*g_setup, safety);
  uint32_t mcu_ms = 0;
  fuzz::RecordReader in(data, size);
  fuzz::Record rec;
  while (in.next(rec)) {
    switch (rec.tag % 5) {
      case 0:
        if (r.link_up) r.onLinkBytes(rec.body);  // nothing arrives on a link that is down
        break;
      case 1:
        if (r.serial_open) r.onSerialBytes(rec.body);
        break;
      case 2: {
        if (!r.serial_open) break;
        // A sensor frame with a good CRC, so that mutations reach the core.
        std::array<uint8_t, 2 + serial::kSensorFramePayload + 2> raw{};
        raw[0] = static_cast<uint8_t>(serial::MsgId::kSensorFrame);
        std::copy_n(rec.body.begin(), std::min(rec.body.size(), serial::kSensorFramePayload), raw.begin() + 2);
        const int repeat = (rec.tag >> 5) + 1;
        for (int i = 0; i < repeat; ++i) {
          raw[1] = r.seq++;
          if (i > 0) {  // the MCU clock moves on 10 ms per frame
            mcu_ms += 10;
            for (int b = 0; b < 4; ++b) raw[2 + b] = static_cast<uint8_t>(mcu_ms >> (8 * b));
          } else {
            mcu_ms = static_cast<uint32_t>(raw[2] | raw[3] << 8 | raw[4] << 16) | static_cast<uint32_t>(raw[5]) << 24;
          }
          const uint16_t crc = serial::crc16CcittFalse({raw.data(), raw.size() - 2});
          raw[raw.size() - 2] = static_cast<uint8_t>(crc);
          raw[raw.size() - 1] = static_cast<uint8_t>(crc >> 8);
          std::array<uint8_t, serial::kMaxEncodedFrame + 1> enc{};
          const std::size_t n = serial::cobsEncode(raw, enc);
          enc[n] = 0;
          r.onSerialBytes({enc.data(), n + 1});
        }
        break;
      }
      case 3: {
        r.t += (rec.body.empty() ? 10 : rec.body[0]) * 1e-3;
        if (const auto c = r.core.onTimer(r.t)) checkWheels(r.core, *c);
        break;
      }
      case 4: {
        const uint8_t bits = rec.body.empty() ? 0 : rec.body[0];
        const bool up = bits & 1, open = bits & 2;
        if (up != r.link_up) {
          if (up) {
            r.core.onLinkUp(r.t);
            r.link = net::DelimitedDecoder{net::kDefaultMaxFrame};  // a new connection
          } else {
            r.core.onLinkDown(r.t, "fuzz");
          }
          r.link_up = up;
        }
        if (open != r.serial_open) {
          r.core.onSerialState(open, r.t);
          r.serial_open = open;
        }
        if (bits & 4) {
          behavior::CameraLook look;
          const std::size_t n = rec.body.size() > 1 ? rec.body[1] % 9 : 0;
          const auto i16 = [&](std::size_t at) {
            return at + 1 < rec.body.size() ? static_cast<int16_t>(rec.body[at] | rec.body[at + 1] << 8) : int16_t{0};
          };
          for (std::size_t k = 0; k < n; ++k) {
            const int16_t b = i16(2 + 4 * k), d = i16(4 + 4 * k);
            look.add({b == 0x7fff ? std::nan("") : b * 1e-4, d == 0x7fff ? std::nan("") : d * 1e-3});
          }
          r.core.onCameraLook(look);
        }
        checkWheels(r.core, r.core.commandNow());
        break;
      }
    }
    r.drain();
  }
  return 0;
}
