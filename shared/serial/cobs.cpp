#include "shared/serial/cobs.hpp"

namespace inspect::serial {

std::size_t cobsEncode(std::span<const uint8_t> in, std::span<uint8_t> out) {
  if (in.size() > kMaxRawFrame || out.size() < in.size() + 1) return 0;
  std::size_t code_pos = 0;
  std::size_t w = 1;
  uint8_t code = 1;
  for (uint8_t b : in) {
    if (b == 0) {
      out[code_pos] = code;
      code_pos = w++;
      code = 1;
    } else {
      out[w++] = b;
      ++code;
    }
  }
  out[code_pos] = code;
  return w;
}

std::optional<std::size_t> cobsDecode(std::span<const uint8_t> in, std::span<uint8_t> out) {
  std::size_t r = 0;
  std::size_t w = 0;
  while (r < in.size()) {
    const uint8_t code = in[r++];
    if (code == 0) return std::nullopt;                 // a zero never appears inside a frame
    if (r + code - 1 > in.size()) return std::nullopt;  // block runs past the end
    for (uint8_t i = 1; i < code; ++i) {
      const uint8_t b = in[r++];
      if (b == 0 || w >= out.size()) return std::nullopt;
      out[w++] = b;
    }
    // A block shorter than 0xFF implies a zero byte, except after the last block.
    if (code != 0xFF && r < in.size()) {
      if (w >= out.size()) return std::nullopt;
      out[w++] = 0;
    }
  }
  return w;
}

}  // namespace inspect::serial
