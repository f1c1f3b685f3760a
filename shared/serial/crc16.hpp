#pragma once
// CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, no reflection, xorout 0.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace inspect::serial {

namespace detail {
constexpr std::array<uint16_t, 256> makeCrcTable() {
  std::array<uint16_t, 256> t{};
  for (unsigned i = 0; i < 256; ++i) {
    uint16_t c = static_cast<uint16_t>(i << 8);
    for (int b = 0; b < 8; ++b) c = (c & 0x8000) ? static_cast<uint16_t>((c << 1) ^ 0x1021) : static_cast<uint16_t>(c << 1);
    t[i] = c;
  }
  return t;
}
inline constexpr auto kCrcTable = makeCrcTable();
}  // namespace detail

/// CRC-16/CCITT-FALSE of a byte range (check value of "123456789" is 0x29B1).
constexpr uint16_t crc16CcittFalse(std::span<const uint8_t> data, uint16_t crc = 0xFFFF) {
  for (uint8_t b : data) crc = static_cast<uint16_t>((crc << 8) ^ detail::kCrcTable[((crc >> 8) ^ b) & 0xFF]);
  return crc;
}

}  // namespace inspect::serial
