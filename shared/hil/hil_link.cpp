#include "shared/hil/hil_link.hpp"

#include "shared/serial/wire_io.hpp"

namespace inspect::hil {
namespace {

void write(serial::WireWriter& w, const HilEncoders& e) {
  for (auto v : e.counter) w.u16(v);
  for (auto v : e.rate_counts_s) w.i32(v);
  w.u16(e.board_ms);
}

void write(serial::WireWriter& w, const HilSensors& in) {
  w.u8(in.echo_count);
  w.u8(in.echo_flags);
  w.u32(in.echo_width_us);
  for (auto v : in.gas_adc) w.u16(v);
  w.u16(in.battery_adc);
  w.u8(in.grayscale);
  w.u8(in.switches);
}

void write(serial::WireWriter& w, const HilOutputs& out) {
  w.u32(out.mcu_time_ms);
  for (auto v : out.duty_1e4) w.i16(v);
  w.u8(out.flags);
  w.u8(out.trigger_sensor);
  w.u8(out.trigger_count);
  for (auto v : out.servo_us) w.u16(v);
  w.u16(out.tick_late_us);
  w.u8(out.input_seq);
  for (auto v : out.setpoint_mrad_s) w.i16(v);
  for (auto v : out.ptz_target_0p1mrad) w.i16(v);
}

void read(serial::WireReader& r, HilEncoders& e) {
  for (auto& v : e.counter) v = r.u16();
  for (auto& v : e.rate_counts_s) v = r.i32();
  e.board_ms = r.u16();
}

void read(serial::WireReader& r, HilSensors& in) {
  in.echo_count = r.u8();
  in.echo_flags = r.u8();
  in.echo_width_us = r.u32();
  for (auto& v : in.gas_adc) v = r.u16();
  in.battery_adc = r.u16();
  in.grayscale = r.u8();
  in.switches = r.u8();
}

void read(serial::WireReader& r, HilOutputs& out) {
  out.mcu_time_ms = r.u32();
  for (auto& v : out.duty_1e4) v = r.i16();
  out.flags = r.u8();
  out.trigger_sensor = r.u8();
  out.trigger_count = r.u8();
  for (auto& v : out.servo_us) v = r.u16();
  out.tick_late_us = r.u16();
  out.input_seq = r.u8();
  for (auto& v : out.setpoint_mrad_s) v = r.i16();
  for (auto& v : out.ptz_target_0p1mrad) v = r.i16();
}

template <class T>
serial::FrameError readAs(serial::WireReader& r, std::size_t size, std::size_t expected, HilMessage& msg) {
  if (size != expected) return serial::FrameError::kBadLength;
  T m;
  read(r, m);
  msg = m;
  return serial::FrameError::kNone;
}

HilId idOf(const HilMessage& m) {
  if (std::holds_alternative<HilEncoders>(m)) return HilId::kEncoders;
  if (std::holds_alternative<HilSensors>(m)) return HilId::kSensors;
  return HilId::kOutputs;
}


}  // namespace

serial::EncodedFrame encodeHil(const HilMessage& msg, uint8_t seq) {
  std::array<uint8_t, 32> payload{};
  serial::WireWriter w{payload.data()};
  std::visit([&](const auto& m) { write(w, m); }, msg);
  return serial::encodeRawFrame(static_cast<uint8_t>(idOf(msg)), seq, {payload.data(), w.n});
}

serial::FrameError decodeHil(std::span<const uint8_t> cobs_bytes, HilMessage& msg, uint8_t& seq) {
  serial::RawFrame f;
  if (const auto err = serial::decodeRawFrame(cobs_bytes, f); err != serial::FrameError::kNone) return err;
  seq = f.seq;
  serial::WireReader r{f.payload.data()};
  switch (static_cast<HilId>(f.id)) {
    case HilId::kEncoders: return readAs<HilEncoders>(r, f.payload.size(), kHilEncodersPayload, msg);
    case HilId::kSensors: return readAs<HilSensors>(r, f.payload.size(), kHilSensorsPayload, msg);
    case HilId::kOutputs: return readAs<HilOutputs>(r, f.payload.size(), kHilOutputsPayload, msg);
  }
  return serial::FrameError::kUnknownId;
}

}  // namespace inspect::hil
