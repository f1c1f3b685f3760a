#include "shared/serial/frame_codec.hpp"

#include <type_traits>

#include "shared/serial/crc16.hpp"
#include "shared/serial/wire_io.hpp"

namespace inspect::serial {
namespace {

using Writer = WireWriter;
using Reader = WireReader;

MsgId idOf(const Message& m) {
  return std::visit(
      [](const auto& v) {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, SensorFrame>) return MsgId::kSensorFrame;
        if constexpr (std::is_same_v<T, WheelCommand>) return MsgId::kWheelCommand;
        if constexpr (std::is_same_v<T, Heartbeat>) return MsgId::kHeartbeat;
        if constexpr (std::is_same_v<T, PtzCommand>) return MsgId::kPtzCommand;
      },
      m);
}

void writePayload(Writer& w, const SensorFrame& s) {
  w.u32(s.mcu_time_ms);
  for (auto v : s.wheel_speed_mrad_s) w.i16(v);
  for (auto v : s.wheel_disp_0p1mm) w.i32(v);
  w.i16(s.heading_0p1mrad);
  for (auto v : s.ultrasonic_mm) w.u16(v);
  w.u8(s.grayscale);
  for (auto v : s.gas_raw) w.u16(v);
  w.u16(s.battery_mv);
  w.u16(s.faults);
  w.u8(s.cmd_seq_echo);
}
void writePayload(Writer& w, const WheelCommand& c) {
  w.i16(c.left_mrad_s);
  w.i16(c.right_mrad_s);
  w.u8(c.flags);
}
void writePayload(Writer& w, const Heartbeat& h) { w.u32(h.host_time_ms); }
void writePayload(Writer& w, const PtzCommand& c) {
  w.i16(c.pan_0p1mrad);
  w.i16(c.tilt_0p1mrad);
  w.u8(c.flags);
}

void readPayload(Reader& r, SensorFrame& s) {
  s.mcu_time_ms = r.u32();
  for (auto& v : s.wheel_speed_mrad_s) v = r.i16();
  for (auto& v : s.wheel_disp_0p1mm) v = r.i32();
  s.heading_0p1mrad = r.i16();
  for (auto& v : s.ultrasonic_mm) v = r.u16();
  s.grayscale = r.u8();
  for (auto& v : s.gas_raw) v = r.u16();
  s.battery_mv = r.u16();
  s.faults = r.u16();
  s.cmd_seq_echo = r.u8();
}
void readPayload(Reader& r, WheelCommand& c) {
  c.left_mrad_s = r.i16();
  c.right_mrad_s = r.i16();
  c.flags = r.u8();
}
void readPayload(Reader& r, Heartbeat& h) { h.host_time_ms = r.u32(); }
void readPayload(Reader& r, PtzCommand& c) {
  c.pan_0p1mrad = r.i16();
  c.tilt_0p1mrad = r.i16();
  c.flags = r.u8();
}

template <class T>
bool readAs(Reader& r, std::size_t payload_len, std::size_t expected, Message& out) {
  if (payload_len != expected) return false;
  T v;
  readPayload(r, v);
  out = v;
  return true;
}

}  // namespace

EncodedFrame encodeRawFrame(uint8_t id, uint8_t seq, std::span<const uint8_t> payload) {
  std::array<uint8_t, kMaxRawFrame> raw{};
  Writer w{raw.data()};
  w.u8(id);
  w.u8(seq);
  for (uint8_t b : payload) w.u8(b);
  const uint16_t crc = crc16CcittFalse({raw.data(), w.n});
  w.u16(crc);
  EncodedFrame f;
  f.seq = seq;
  f.size = cobsEncode({raw.data(), w.n}, f.bytes);
  f.bytes[f.size++] = 0x00;
  return f;
}

FrameError decodeRawFrame(std::span<const uint8_t> cobs_bytes, RawFrame& out) {
  const auto n = cobsDecode(cobs_bytes, out.raw);
  if (!n) return FrameError::kBadCobs;
  if (*n < 4) return FrameError::kBadLength;
  const std::size_t body = *n - 2;
  const uint16_t want = static_cast<uint16_t>(out.raw[body] | (out.raw[body + 1] << 8));
  if (crc16CcittFalse({out.raw.data(), body}) != want) return FrameError::kBadCrc;
  out.id = out.raw[0];
  out.seq = out.raw[1];
  out.payload = {out.raw.data() + 2, body - 2};
  return FrameError::kNone;
}

EncodedFrame FrameEncoder::encode(const Message& msg) {
  std::array<uint8_t, kMaxRawFrame> payload{};
  Writer w{payload.data()};
  std::visit([&](const auto& v) { writePayload(w, v); }, msg);
  const auto id = static_cast<uint8_t>(idOf(msg));
  return encodeRawFrame(id, next_seq_[id]++, {payload.data(), w.n});
}

FrameError decodeFrame(std::span<const uint8_t> cobs_bytes, Message& msg, uint8_t& seq) {
  RawFrame f;
  if (const FrameError err = decodeRawFrame(cobs_bytes, f); err != FrameError::kNone) return err;
  seq = f.seq;
  Reader r{f.payload.data()};
  const std::size_t payload = f.payload.size();
  bool ok = false;
  switch (static_cast<MsgId>(f.id)) {
    case MsgId::kSensorFrame: ok = readAs<SensorFrame>(r, payload, kSensorFramePayload, msg); break;
    case MsgId::kWheelCommand: ok = readAs<WheelCommand>(r, payload, kWheelCommandPayload, msg); break;
    case MsgId::kHeartbeat: ok = readAs<Heartbeat>(r, payload, kHeartbeatPayload, msg); break;
    case MsgId::kPtzCommand: ok = readAs<PtzCommand>(r, payload, kPtzCommandPayload, msg); break;
    default: return FrameError::kUnknownId;
  }
  return ok ? FrameError::kNone : FrameError::kBadLength;
}

bool FrameDecoder::accept(FrameError err, const Message& msg, uint8_t seq) {
  switch (err) {
    case FrameError::kNone: break;
    case FrameError::kBadCobs: ++counters_.bad_cobs; break;
    case FrameError::kBadCrc: ++counters_.bad_crc; break;
    case FrameError::kBadLength: ++counters_.bad_length; break;
    case FrameError::kUnknownId: ++counters_.unknown_id; break;
    case FrameError::kOverflow: ++counters_.overflow; break;
  }
  if (err != FrameError::kNone) {
    last_error_ = err;
    return false;
  }
  ++counters_.frames_ok;
  const auto id = static_cast<uint8_t>(idOf(msg));
  if (last_seq_[id] >= 0) {
    const uint8_t expected = static_cast<uint8_t>(last_seq_[id] + 1);
    counters_.seq_gaps += static_cast<uint8_t>(seq - expected);
  }
  last_seq_[id] = seq;
  return true;
}

const char* toString(FrameError e) {
  switch (e) {
    case FrameError::kNone: return "ok";
    case FrameError::kBadCobs: return "bad COBS encoding";
    case FrameError::kBadCrc: return "CRC mismatch";
    case FrameError::kBadLength: return "bad length";
    case FrameError::kUnknownId: return "unknown message id";
    case FrameError::kOverflow: return "frame too long";
  }
  return "?";
}

}  // namespace inspect::serial
