// Retransmission (RFC 4588 RTX, the sender's history, the receiver's NACK
// list) with the real packetizer's packets.
#include <gtest/gtest.h>

#include <set>

#include "shared/video/rtx.hpp"

using namespace inspect::video;

namespace {

// Packets of one made-up access unit: an IDR of 3000 bytes in FU-A fragments.
std::vector<std::vector<uint8_t>> somePackets(uint16_t first_seq) {
  std::vector<uint8_t> au = {0, 0, 0, 1, 0x65};
  for (int k = 0; k < 3000; ++k) au.push_back(static_cast<uint8_t>(k * 7 + 1));
  H264Packetizer pk(0xC0FFEE, 1000, first_seq);
  std::vector<std::vector<uint8_t>> out;
  pk.packetize(au, 90000, 123456789, out);
  return out;
}

}  // namespace

TEST(Rtx, WrapsAndUnwrapsToTheSameBytesKeepingTheCaptureTime) {
  const auto packets = somePackets(65534);  // the original numbers wrap
  ASSERT_GE(packets.size(), 3u);
  for (std::size_t i = 0; i < packets.size(); ++i) {
    const auto rtx = makeRtx(packets[i], 0xBEEF, kRtxPayloadType, static_cast<uint16_t>(500 + i));
    ASSERT_TRUE(rtx.has_value());
    RtpPacket r, o;
    ASSERT_EQ(parseRtp(*rtx, r), RtpError::kNone);
    ASSERT_EQ(parseRtp(packets[i], o), RtpError::kNone);
    EXPECT_EQ(r.payload_type, kRtxPayloadType);
    EXPECT_EQ(r.ssrc, 0xBEEFu);
    EXPECT_EQ(r.seq, 500 + i);
    EXPECT_EQ(r.timestamp, o.timestamp);
    EXPECT_EQ(r.marker, o.marker);
    EXPECT_EQ(r.capture_us, o.capture_us) << "the header extension travels with it";
    ASSERT_EQ(r.payload.size(), o.payload.size() + 2);
    EXPECT_EQ(r.payload[0] << 8 | r.payload[1], o.seq) << "OSN first";
    std::vector<uint8_t> back;
    ASSERT_EQ(unwrapRtx(*rtx, kRtxPayloadType, kPayloadType, 0xC0FFEE, back), RtxError::kNone);
    EXPECT_EQ(back, packets[i]);
  }
}

TEST(Rtx, BadRtxDatagramsNameTheFault) {
  const auto packets = somePackets(1);
  std::vector<uint8_t> out;
  EXPECT_EQ(unwrapRtx(std::vector<uint8_t>{1, 2, 3}, kRtxPayloadType, kPayloadType, 1, out), RtxError::kNotRtp);
  EXPECT_EQ(unwrapRtx(packets[0], kRtxPayloadType, kPayloadType, 1, out), RtxError::kWrongPayloadType);
  auto rtx = makeRtx(packets[1], 2, kRtxPayloadType, 0);
  ASSERT_TRUE(rtx.has_value());
  rtx->resize(kRtpHeaderSize + 1);  // one byte of OSN
  EXPECT_EQ(unwrapRtx(*rtx, kRtxPayloadType, kPayloadType, 1, out), RtxError::kNoOriginalSeq);
  EXPECT_FALSE(makeRtx(std::vector<uint8_t>{0x80}, 2, kRtxPayloadType, 0).has_value());
  for (auto e : {RtxError::kNotRtp, RtxError::kWrongPayloadType, RtxError::kNoOriginalSeq})
    EXPECT_STRNE(toString(e), "?");
}

TEST(RetransmissionHistory, BoundedInCountAndAgeAcrossTheWrap) {
  RetransmissionHistory h(100, 1'000'000);
  uint16_t seq = 65500;
  for (int k = 0; k < 300; ++k, ++seq) h.remember(seq, std::vector<uint8_t>(50, static_cast<uint8_t>(k)), k * 1000ull);
  EXPECT_EQ(h.size(), 100u);
  EXPECT_EQ(h.bytes(), 100u * 50u);
  const uint16_t newest = static_cast<uint16_t>(seq - 1), oldest_kept = static_cast<uint16_t>(seq - 100);
  ASSERT_NE(h.find(newest, 300'000), nullptr);
  EXPECT_EQ(h.find(newest, 300'000)->front(), static_cast<uint8_t>(299));
  ASSERT_NE(h.find(oldest_kept, 300'000), nullptr);
  EXPECT_EQ(h.find(oldest_kept, 300'000)->front(), 200);
  EXPECT_EQ(h.find(static_cast<uint16_t>(seq - 101), 300'000), nullptr) << "pushed out by the count";
  EXPECT_EQ(h.find(oldest_kept, 1'250'000), nullptr) << "too old to be worth sending";
  EXPECT_NE(h.find(newest, 1'250'000), nullptr);
  RetransmissionHistory none(0, 1'000'000);
  none.remember(1, std::vector<uint8_t>(10), 0);
  EXPECT_EQ(none.find(1, 0), nullptr);
}

TEST(NackList, NacksAGapAfterTheReorderWaitThenRetriesEveryOneAndAHalfRtt) {
  NackList n;
  n.onPacket(100, 0);
  n.onPacket(101, 1000);
  n.onPacket(104, 2000);  // 102, 103 missing
  EXPECT_TRUE(n.missing(102));
  EXPECT_TRUE(n.missing(103));
  EXPECT_TRUE(n.due(3000, 20000).empty()) << "within the reorder wait";
  n.onPacket(103, 4000);  // was only reordered
  EXPECT_FALSE(n.missing(103));
  EXPECT_EQ(n.due(7000, 20000), std::vector<uint16_t>{102});
  EXPECT_TRUE(n.due(20000, 20000).empty()) << "retry after 1.5 RTT = 30 ms";
  EXPECT_EQ(n.due(37000, 20000), std::vector<uint16_t>{102});
  EXPECT_EQ(n.due(67000, 20000), std::vector<uint16_t>{102});
  EXPECT_TRUE(n.due(200000, 20000).empty()) << "three tries at most";
  EXPECT_EQ(n.nacked(), 3u);
  EXPECT_EQ(n.expire(0, 97000, 20000), std::vector<uint16_t>{102}) << "its last try had its 30 ms";
  EXPECT_EQ(n.givenUp(), 1u);
  EXPECT_EQ(n.size(), 0u);
}

TEST(NackList, ARetransmissionCountsAsRecoveredAndTheDeadlineGivesUp) {
  NackList n;
  n.onPacket(65530, 0);
  n.onPacket(2, 1000);  // 65531..1 missing across the wrap: 7 packets
  EXPECT_EQ(n.size(), 7u);
  const auto first = n.due(10000, 10000);
  EXPECT_EQ(first.size(), 7u);
  EXPECT_EQ(std::set<uint16_t>(first.begin(), first.end()), (std::set<uint16_t>{65531, 65532, 65533, 65534, 65535, 0, 1}));
  n.onPacket(65535, 20000);
  n.onPacket(0, 20000);
  EXPECT_EQ(n.recovered(), 2u);
  // The frame of the rest can no longer be shown: everything first missed before 5 ms goes.
  EXPECT_EQ(n.expire(5000, 30000, 10000).size(), 5u);
  EXPECT_EQ(n.size(), 0u);
  n.onPacket(65534, 40000);  // an old packet that is not missing: nothing happens
  EXPECT_EQ(n.size(), 0u);
}

TEST(NackList, AHugeJumpKeepsOnlyTheNewestOfTheGap) {
  NackSettings s;
  s.max_missing = 64;
  NackList n(s);
  n.onPacket(0, 0);
  n.onPacket(1000, 1000);
  EXPECT_EQ(n.size(), 64u);
  EXPECT_TRUE(n.missing(999));
  EXPECT_FALSE(n.missing(935));
  EXPECT_EQ(n.givenUp(), 999u - 64u);
}
