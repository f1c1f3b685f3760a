// Serial codec: CRC, COBS, frames, stream decoding with garbage and resync.
#include <gtest/gtest.h>

#include <random>
#include <string_view>
#include <vector>

#include "shared/serial/crc16.hpp"
#include "shared/serial/frame_codec.hpp"

using namespace inspect::serial;

namespace {
std::vector<uint8_t> bytesOf(std::string_view s) { return {s.begin(), s.end()}; }

SensorFrame sampleSensor() {
  SensorFrame s;
  s.mcu_time_ms = 123456;
  s.wheel_speed_mrad_s = {2500, -2499};
  s.wheel_disp_0p1mm = {-1234567, 7654321};
  s.heading_0p1mrad = -31415;
  s.ultrasonic_mm = {1000, kNoEcho, 0, 300};
  s.grayscale = 0xA5;
  s.gas_raw = {0, 1, 0xFFFF, 2090};
  s.battery_mv = 24100;
  s.faults = kFaultWatchdog | kFaultHostSilent;
  s.cmd_seq_echo = 200;
  return s;
}

struct Collected {
  std::vector<Message> msgs;
  std::vector<uint8_t> seqs;
};

Collected feedAll(FrameDecoder& d, const std::vector<uint8_t>& bytes) {
  Collected c;
  d.feed(bytes, [&](const Message& m, uint8_t seq) {
    c.msgs.push_back(m);
    c.seqs.push_back(seq);
  });
  return c;
}
}  // namespace

TEST(Crc16, CheckValue) {
  const auto b = bytesOf("123456789");
  EXPECT_EQ(crc16CcittFalse(b), 0x29B1);
  EXPECT_EQ(crc16CcittFalse({}), 0xFFFF);
}

TEST(Cobs, RoundTripsEdgeCases) {
  std::vector<std::vector<uint8_t>> cases = {{}, {0}, {0, 0}, {1}, {1, 0, 2}, {0, 1, 0}};
  std::vector<uint8_t> long_nonzero(254);
  for (std::size_t i = 0; i < long_nonzero.size(); ++i) long_nonzero[i] = static_cast<uint8_t>(i % 255 + 1);
  cases.push_back(long_nonzero);
  std::vector<uint8_t> zeros(254, 0);
  cases.push_back(zeros);
  for (const auto& raw : cases) {
    std::array<uint8_t, kMaxEncodedFrame> enc{};
    const std::size_t n = cobsEncode(raw, enc);
    ASSERT_EQ(n, raw.size() + 1);
    for (std::size_t i = 0; i < n; ++i) EXPECT_NE(enc[i], 0) << "encoded frame must contain no zero";
    std::array<uint8_t, kMaxRawFrame> dec{};
    const auto m = cobsDecode({enc.data(), n}, dec);
    ASSERT_TRUE(m.has_value());
    ASSERT_EQ(*m, raw.size());
    EXPECT_TRUE(std::equal(raw.begin(), raw.end(), dec.begin()));
  }
}

TEST(Cobs, RejectsInvalid) {
  std::array<uint8_t, kMaxRawFrame> dec{};
  const std::vector<uint8_t> zero_inside = {3, 1, 0};
  EXPECT_FALSE(cobsDecode(zero_inside, dec));
  const std::vector<uint8_t> runs_past = {5, 1, 2};
  EXPECT_FALSE(cobsDecode(runs_past, dec));
  std::vector<uint8_t> too_long(300, 1);
  std::array<uint8_t, 400> enc{};
  EXPECT_EQ(cobsEncode(too_long, enc), 0u);
}

TEST(SerialFrame, EveryMessageRoundTrips) {
  FrameEncoder enc;
  FrameDecoder dec;
  const std::vector<Message> msgs = {sampleSensor(), WheelCommand{-5000, 5000, WheelCommand::kEnable}, Heartbeat{0xDEADBEEF},
                                     PtzCommand{-15708, 7854, 1}};
  std::vector<uint8_t> stream;
  for (const auto& m : msgs) {
    const auto f = enc.encode(m);
    stream.insert(stream.end(), f.span().begin(), f.span().end());
  }
  const auto got = feedAll(dec, stream);
  ASSERT_EQ(got.msgs.size(), msgs.size());
  for (std::size_t i = 0; i < msgs.size(); ++i) EXPECT_EQ(got.msgs[i], msgs[i]);
  EXPECT_EQ(dec.counters().frames_ok, 4u);
  EXPECT_EQ(dec.counters().errors(), 0u);
}

TEST(SerialFrame, SensorFrameSizeOnTheWire) {
  FrameEncoder enc;
  const auto f = enc.encode(sampleSensor());
  // id + seq + 40 payload + CRC = 44 raw; COBS adds 1 (frame < 254), delimiter 1.
  EXPECT_EQ(f.size, 46u);
  // 100 Hz at 115200 8N1 (11520 bytes/s) must use well under half the line.
  EXPECT_LT(f.size * 100.0 / 11520.0, 0.45);
}

TEST(SerialFrame, SplitAtEveryByteBoundary) {
  FrameEncoder enc;
  const auto f1 = enc.encode(sampleSensor());
  const auto f2 = enc.encode(WheelCommand{100, 200, 1});
  std::vector<uint8_t> stream(f1.span().begin(), f1.span().end());
  stream.insert(stream.end(), f2.span().begin(), f2.span().end());
  for (std::size_t cut = 0; cut <= stream.size(); ++cut) {
    FrameDecoder dec;
    std::size_t n = 0;
    auto cb = [&](const Message&, uint8_t) { ++n; };
    dec.feed(std::span(stream).first(cut), cb);
    dec.feed(std::span(stream).subspan(cut), cb);
    EXPECT_EQ(n, 2u) << "cut at " << cut;
    EXPECT_EQ(dec.counters().errors(), 0u);
  }
}

TEST(SerialFrame, TruncatedFrameIsCountedAndNextFrameSurvives) {
  FrameEncoder enc;
  const auto f1 = enc.encode(sampleSensor());
  const auto f2 = enc.encode(sampleSensor());
  std::vector<uint8_t> stream(f1.span().begin(), f1.span().begin() + 20);
  stream.push_back(0);  // the frame ends early
  stream.insert(stream.end(), f2.span().begin(), f2.span().end());
  FrameDecoder dec;
  const auto got = feedAll(dec, stream);
  ASSERT_EQ(got.msgs.size(), 1u);
  EXPECT_EQ(got.seqs[0], f2.seq);
  EXPECT_EQ(dec.counters().errors(), 1u);
}

TEST(SerialFrame, EverySingleBitFlipIsRejected) {
  FrameEncoder enc;
  const auto f = enc.encode(WheelCommand{1234, -1234, 1});
  for (std::size_t byte = 0; byte + 1 < f.size; ++byte) {
    for (int bit = 0; bit < 8; ++bit) {
      auto bad = std::vector<uint8_t>(f.span().begin(), f.span().end());
      bad[byte] ^= static_cast<uint8_t>(1u << bit);
      FrameDecoder dec;
      const auto got = feedAll(dec, bad);
      EXPECT_TRUE(got.msgs.empty()) << "flip byte " << byte << " bit " << bit;
    }
  }
}

TEST(SerialFrame, CountsEachErrorKind) {
  // Unknown id with a valid CRC.
  std::array<uint8_t, 6> raw = {0x7E, 0, 1, 2, 0, 0};
  const uint16_t crc = crc16CcittFalse({raw.data(), 4});
  raw[4] = static_cast<uint8_t>(crc);
  raw[5] = static_cast<uint8_t>(crc >> 8);
  std::array<uint8_t, 16> enc{};
  std::size_t n = cobsEncode(raw, enc);
  std::vector<uint8_t> stream(enc.begin(), enc.begin() + static_cast<long>(n));
  stream.push_back(0);
  // Known id with the wrong payload length, valid CRC.
  std::array<uint8_t, 5> raw2 = {0x21, 0, 9, 0, 0};
  const uint16_t crc2 = crc16CcittFalse({raw2.data(), 3});
  raw2[3] = static_cast<uint8_t>(crc2);
  raw2[4] = static_cast<uint8_t>(crc2 >> 8);
  n = cobsEncode(raw2, enc);
  stream.insert(stream.end(), enc.begin(), enc.begin() + static_cast<long>(n));
  stream.push_back(0);
  // Overlong run of bytes without a delimiter.
  stream.insert(stream.end(), 400, 0x55);
  stream.push_back(0);
  FrameDecoder dec;
  EXPECT_TRUE(feedAll(dec, stream).msgs.empty());
  EXPECT_EQ(dec.counters().unknown_id, 1u);
  EXPECT_EQ(dec.counters().bad_length, 1u);
  EXPECT_EQ(dec.counters().overflow, 1u);
}

TEST(SerialFrame, SequenceGapsAreCountedAcrossWrap) {
  FrameEncoder enc;
  FrameDecoder dec;
  std::vector<uint8_t> stream;
  for (int i = 0; i < 300; ++i) {
    const auto f = enc.encode(Heartbeat{static_cast<uint32_t>(i)});
    if (i % 10 == 5) continue;  // lose every tenth frame
    stream.insert(stream.end(), f.span().begin(), f.span().end());
  }
  const auto got = feedAll(dec, stream);
  EXPECT_EQ(got.msgs.size(), 270u);
  EXPECT_EQ(dec.counters().seq_gaps, 30u);
}

TEST(SerialFrame, RandomGarbageNeverDecodesAsAWheelCommand) {
  // Resync after garbage, and a garbage frame is (almost surely) not a message.
  std::mt19937 rng(42);
  std::uniform_int_distribution<int> byte(0, 255);
  FrameEncoder enc;
  FrameDecoder dec;
  std::size_t valid_sent = 0, valid_got = 0, foreign = 0;
  for (int round = 0; round < 2000; ++round) {
    std::vector<uint8_t> stream;
    const int junk = byte(rng) % 40;
    for (int i = 0; i < junk; ++i) stream.push_back(static_cast<uint8_t>(byte(rng)));
    stream.push_back(0);
    const WheelCommand cmd{static_cast<int16_t>(round), static_cast<int16_t>(-round), 1};
    const auto f = enc.encode(cmd);
    stream.insert(stream.end(), f.span().begin(), f.span().end());
    ++valid_sent;
    dec.feed(stream, [&](const Message& m, uint8_t) {
      const auto* w = std::get_if<WheelCommand>(&m);
      if (w && *w == cmd) ++valid_got;
      else ++foreign;
    });
  }
  EXPECT_EQ(valid_got, valid_sent);
  EXPECT_EQ(foreign, 0u);
  EXPECT_GT(dec.counters().errors(), 1000u);
}

TEST(SerialFrame, DocumentedHeartbeatExample) {
  // docs/serial-protocol.md, "Example".
  FrameEncoder enc;
  for (int i = 0; i < 3; ++i) enc.encode(Heartbeat{0});
  const auto f = enc.encode(Heartbeat{1000});
  const std::vector<uint8_t> want = {0x05, 0x21, 0x03, 0xE8, 0x03, 0x01, 0x03, 0x13, 0xC8, 0x00};
  EXPECT_EQ(std::vector<uint8_t>(f.span().begin(), f.span().end()), want);
}
