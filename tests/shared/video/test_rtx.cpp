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

TEST(NackList, NacksAGapAfterTheReorderWaitThenRetriesEveryRttAndAQuarter) {
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
  EXPECT_TRUE(n.due(31000, 20000).empty()) << "retry after 1.25 RTT = 25 ms";
  EXPECT_EQ(n.due(32000, 20000), std::vector<uint16_t>{102});
  EXPECT_EQ(n.due(57000, 20000), std::vector<uint16_t>{102});
  EXPECT_EQ(n.due(82000, 20000), std::vector<uint16_t>{102});
  EXPECT_TRUE(n.due(200000, 20000).empty()) << "four tries at most";
  EXPECT_EQ(n.nacked(), 4u);
  EXPECT_TRUE(n.expire(0, 106000, 20000).empty()) << "its last try still has time";
  EXPECT_EQ(n.expire(0, 107000, 20000), std::vector<uint16_t>{102}) << "its last try had its 25 ms";
  EXPECT_EQ(n.givenUp(), 1u);
  EXPECT_EQ(n.size(), 0u);
}

TEST(NackList, ATailProbeAsksForThePacketAfterTheNewestAndIsFilledByIt) {
  // A frame's marker packet lost: nothing after it shows the loss until the
  // next frame, so the receiver probes for the next sequence number.
  NackList n;
  EXPECT_FALSE(n.probeTail(0)) << "nothing seen yet";
  n.onPacket(10, 0);
  n.onPacket(11, 100);
  EXPECT_TRUE(n.probeTail(4100));
  EXPECT_TRUE(n.missing(12));
  EXPECT_EQ(n.highest(), 12);
  EXPECT_EQ(n.due(9100, 20000), std::vector<uint16_t>{12}) << "after the reorder wait, like any gap";
  n.onPacket(12, 25000);  // its retransmission (or the late original)
  EXPECT_FALSE(n.missing(12));
  EXPECT_EQ(n.recovered(), 1u);
  EXPECT_TRUE(n.probeTail(30000));  // 13 probed; the next frame's 13, 14 arrive
  n.onPacket(14, 33000);
  EXPECT_TRUE(n.missing(13)) << "still missing: 14 came, 13 did not";
  n.onPacket(13, 34000);
  EXPECT_EQ(n.size(), 0u);
  EXPECT_EQ(n.tailProbes(), 2u);
}

TEST(NackList, ExpireBeforeGivesUpOnlyWhatTheReorderBufferReleasedWithout) {
  NackList n;
  n.onPacket(65533, 0);
  n.onPacket(3, 0);  // 65534..2 missing
  ASSERT_TRUE(n.probeTail(5000));  // 4
  EXPECT_EQ(n.size(), 6u);
  EXPECT_EQ(n.expireBefore(1), 3u) << "65534, 65535, 0: before 1 across the wrap";
  EXPECT_TRUE(n.missing(1));
  EXPECT_TRUE(n.missing(4)) << "a probe past the released ones stays";
  EXPECT_EQ(n.firstMissedUs(1), std::optional<uint64_t>(0));
  EXPECT_EQ(n.firstMissedUs(4), std::optional<uint64_t>(5000)) << "the probe's time";
  EXPECT_EQ(n.firstMissedUs(3), std::nullopt) << "arrived";
  EXPECT_EQ(n.expireBefore(4), 2u);
  EXPECT_EQ(n.size(), 1u);
  EXPECT_EQ(n.givenUp(), 5u);
}

TEST(RetransmissionHistory, ARepeatedNackWithinTheWindowIsNotResentARetryGoesTwice) {
  RetransmissionHistory h(100, 1'000'000);
  h.remember(7, std::vector<uint8_t>(20, 7), 0);
  const auto first = h.planRetransmission(7, 10'000, 5'000);
  ASSERT_NE(first.datagram, nullptr);
  EXPECT_EQ(first.copies, 1);
  const auto repeat = h.planRetransmission(7, 11'000, 5'000);  // the receiver's second copy of that NACK
  EXPECT_NE(repeat.datagram, nullptr);
  EXPECT_EQ(repeat.copies, 0);
  const auto retry = h.planRetransmission(7, 40'000, 5'000);  // the first retransmission was lost
  EXPECT_EQ(retry.copies, 2);
  EXPECT_EQ(h.planRetransmission(8, 40'000, 5'000).datagram, nullptr) << "never sent";
  EXPECT_EQ(h.planRetransmission(7, 2'000'000, 5'000).datagram, nullptr) << "too old";
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
