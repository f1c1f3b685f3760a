#pragma once
// The sensor frames in a byte stream the MCU emulator sent, for tests.
#include <gtest/gtest.h>

#include <cstdint>
#include <variant>
#include <vector>

#include "shared/serial/frame_codec.hpp"

namespace inspect::test {

/// Every SensorFrame of `bytes`; a clean stream from the emulator has no
/// decoder errors and no sequence gaps (checked).
inline std::vector<serial::SensorFrame> decodeSensorFrames(const std::vector<uint8_t>& bytes) {
  serial::FrameDecoder dec;
  std::vector<serial::SensorFrame> out;
  dec.feed(bytes, [&](const serial::Message& m, uint8_t) {
    if (auto* s = std::get_if<serial::SensorFrame>(&m)) out.push_back(*s);
  });
  EXPECT_EQ(dec.counters().errors(), 0u);
  EXPECT_EQ(dec.counters().seq_gaps, 0u);
  return out;
}

}  // namespace inspect::test
