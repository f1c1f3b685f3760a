// Fuzzes the server's side of the robot link without sockets: the delimited
// framing (shared/net/delimited_codec) fed arbitrary chunks, Envelope
// parsing, and what pc_server does with each message in
// RobotSession::handleFrame: the handshake rules (hello_check), then
// telemetry, events and acks into the RobotRegistry, as two robot
// connections interleaved; the operator's side reads the registry back
// (snapshots, the status line, alarms and their acknowledgement).
//
// Input: records (fuzz_records.hpp). tag bit 0 picks connection 0 or 1;
// (tag >> 1) % 4: 0, 1 = link bytes for that connection, 2 = it closes and
// a new one takes its place, 3 = the operator looks (body[0] picks what).
// Each record advances the clock by 1-256 ms.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include <google/protobuf/stubs/logging.h>

#include "inspect_robot/v1/link.pb.h"
#include "pc_server/link/hello_check.hpp"
#include "pc_server/link/robot_registry.hpp"
#include "pc_server/console/status_line.hpp"
#include "shared/net/delimited_codec.hpp"
#include "shared/net/robot_id.hpp"
#include "tests/fuzz/fuzz_records.hpp"

using namespace inspect;
using server::RobotRegistry;

namespace {

struct Connection {
  uint64_t serial = 0;
  std::string address;
  net::DelimitedDecoder decoder{64 * 1024};
  bool open = true;
  bool accepted = false;
  std::string robot_id;
};

// RobotSession::handleFrame without the socket: false = the session closes.
bool handleFrame(Connection& c, RobotRegistry& reg, std::span<const uint8_t> frame, int64_t now_ns) {
  v1::Envelope env;
  if (!net::DelimitedDecoder::parse(frame, env)) return false;
  const auto body = env.body_case();
  if (!c.accepted) {
    if (body != v1::Envelope::kHello) return false;
    const auto why = server::helloRejection(env.hello());
    if (why) {
      FUZZ_CHECK(!why->empty());
      return false;
    }
    FUZZ_CHECK(net::validRobotId(env.hello().robot_id()));
    c.accepted = true;
    c.robot_id = env.hello().robot_id();
    reg.onConnected(c.robot_id, c.address, c.serial, env.hello(), now_ns);
    return true;
  }
  switch (body) {
    case v1::Envelope::kHeartbeat: return true;
    case v1::Envelope::kTelemetry: reg.onTelemetry(c.robot_id, c.serial, env.telemetry(), now_ns); return true;
    case v1::Envelope::kEvent: reg.onEvent(c.robot_id, c.serial, env.event(), now_ns); return true;
    case v1::Envelope::kAck: reg.onAck(c.robot_id, c.serial, env.ack()); return true;
    default: return false;
  }
}

void close(Connection& c, RobotRegistry& reg, const std::string& why, int64_t now_ns) {
  if (c.open && c.accepted) reg.onDisconnected(c.robot_id, c.serial, why, now_ns);
  c.open = false;
}

void look(RobotRegistry& reg, std::span<const uint8_t> body, int64_t now_ns) {
  const uint8_t what = body.empty() ? 0 : body[0];
  const int n = body.size() > 1 ? body[1] : 1;
  switch (what % 6) {
    case 0:
      for (const auto& s : reg.snapshots(now_ns)) {
        const std::optional<server::RobotSnapshot> snap = s;
        FUZZ_CHECK(!server::statusLine(s.id, snap).empty());
        (void)server::statusIsAlarm(snap);
        (void)server::videoReport(s.id, snap, nullptr);
        FUZZ_CHECK(!server::faultNames(s.telemetry.faults()).empty());
      }
      break;
    case 1:
      for (const auto& a : reg.alarms(what & 0x80, "")) FUZZ_CHECK(a.number > 0);
      break;
    case 2: (void)reg.ackAlarm(n, now_ns); break;
    case 3: (void)reg.ackAllAlarms(now_ns); break;
    case 4:
      for (const auto& e : reg.takeEvents()) (void)reg.events(e.robot_id);
      break;
    case 5: {
      const std::string first = reg.firstConnected();
      if (!first.empty()) {
        (void)reg.ack(first, static_cast<uint64_t>(n));
        (void)reg.unackedAlarms(first);
        FUZZ_CHECK(reg.snapshot(first, now_ns).has_value());
      }
      break;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // Fuzzed strings are often not UTF-8: protobuf logs each one (the server would too).
  google::protobuf::SetLogHandler([](google::protobuf::LogLevel, const char*, int, const std::string&) {});
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  RobotRegistry reg;
  uint64_t serials = 0;
  Connection conns[2];
  for (int i = 0; i < 2; ++i) {
    conns[i].serial = ++serials;
    conns[i].address = "127.0.0.1:" + std::to_string(40000 + i);
  }
  int64_t now_ns = 1'000'000'000;
  fuzz::RecordReader in(data, size);
  fuzz::Record r;
  while (in.next(r)) {
    now_ns += (1 + (r.tag >> 3)) * 8'000'000LL;
    Connection& c = conns[r.tag & 1];
    switch ((r.tag >> 1) % 4) {
      case 0:
      case 1: {
        if (!c.open) break;
        c.decoder.append(r.body);
        for (;;) {
          std::span<const uint8_t> frame;
          const auto st = c.decoder.next(frame);
          if (st == net::DelimitedDecoder::Status::kNeedMore) break;
          if (st == net::DelimitedDecoder::Status::kInvalid) {
            FUZZ_CHECK(!c.decoder.error().empty());
            close(c, reg, "framing error: " + c.decoder.error(), now_ns);
            break;
          }
          FUZZ_CHECK(frame.size() <= c.decoder.maxFrame());
          if (!handleFrame(c, reg, frame, now_ns)) {
            close(c, reg, "protocol error", now_ns);
            break;
          }
        }
        break;
      }
      case 2:
        close(c, reg, "closed", now_ns);
        c.serial = ++serials;
        c.decoder = net::DelimitedDecoder{64 * 1024};
        c.open = true;
        c.accepted = false;
        c.robot_id.clear();
        break;
      case 3: look(reg, r.body, now_ns); break;
    }
  }
  FUZZ_CHECK(reg.connectedCount() <= 2);
  return 0;
}
