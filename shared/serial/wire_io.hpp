#pragma once
// Little-endian integers over a fixed buffer: the byte order of every payload
// on the serial line (docs/serial-protocol.md) and on the HIL link
// (docs/firmware.md). No bounds checks: the callers size their buffers from
// the payload sizes they declare.
#include <cstddef>
#include <cstdint>

namespace inspect::serial {

struct WireWriter {
  uint8_t* p;
  std::size_t n = 0;
  void u8(uint8_t v) { p[n++] = v; }
  void u16(uint16_t v) {
    u8(static_cast<uint8_t>(v));
    u8(static_cast<uint8_t>(v >> 8));
  }
  void i16(int16_t v) { u16(static_cast<uint16_t>(v)); }
  void u32(uint32_t v) {
    u16(static_cast<uint16_t>(v));
    u16(static_cast<uint16_t>(v >> 16));
  }
  void i32(int32_t v) { u32(static_cast<uint32_t>(v)); }
};

struct WireReader {
  const uint8_t* p;
  std::size_t n = 0;
  uint8_t u8() { return p[n++]; }
  uint16_t u16() {
    const uint16_t lo = u8();
    return static_cast<uint16_t>(lo | (static_cast<uint16_t>(u8()) << 8));
  }
  int16_t i16() { return static_cast<int16_t>(u16()); }
  uint32_t u32() {
    const uint32_t lo = u16();
    return lo | (static_cast<uint32_t>(u16()) << 16);
  }
  int32_t i32() { return static_cast<int32_t>(u32()); }
};

}  // namespace inspect::serial
