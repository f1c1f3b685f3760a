// RTCP (RFC 3550 reports, RFC 4585 NACK and PLI): builders and the parser
// against each other, hand-made wire bytes, malformed datagrams, and the
// receiver statistics of appendix A.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "shared/video/rtcp.hpp"

using namespace inspect::video;
using namespace inspect::video::rtcp;

TEST(Rtcp, SenderReportWithBlocksAndCnameRoundTrips) {
  std::vector<uint8_t> d;
  const SenderInfo info{0x0123456789ABCDEFULL, 0xDEADBEEF, 1234, 567890};
  ReportBlock b1{0x11111111, 25, 100, 70000, 1800, 0x89ABCDEF, 13107};
  ReportBlock b2{0x22222222, 0, -3, 5, 0, 0, 0};
  const std::vector<ReportBlock> blocks{b1, b2};
  appendSenderReport(d, 0xCAFEBABE, info, blocks);
  appendCname(d, 0xCAFEBABE, "robot1@inspect");
  ASSERT_EQ(d.size() % 4, 0u);
  EXPECT_TRUE(looksLikeRtcp(d));
  Compound c;
  ASSERT_EQ(parseCompound(d, c), RtcpError::kNone);
  ASSERT_EQ(c.sender_reports.size(), 1u);
  const auto& sr = c.sender_reports[0];
  EXPECT_EQ(sr.ssrc, 0xCAFEBABEu);
  EXPECT_EQ(sr.info.ntp, info.ntp);
  EXPECT_EQ(sr.info.rtp_timestamp, info.rtp_timestamp);
  EXPECT_EQ(sr.info.packets, 1234u);
  EXPECT_EQ(sr.info.octets, 567890u);
  ASSERT_EQ(sr.blocks.size(), 2u);
  EXPECT_EQ(sr.blocks[0].ssrc, b1.ssrc);
  EXPECT_EQ(sr.blocks[0].fraction_lost, 25);
  EXPECT_EQ(sr.blocks[0].cumulative_lost, 100);
  EXPECT_EQ(sr.blocks[0].highest_seq, 70000u);
  EXPECT_EQ(sr.blocks[0].jitter, 1800u);
  EXPECT_EQ(sr.blocks[0].lsr, 0x89ABCDEFu);
  EXPECT_EQ(sr.blocks[0].dlsr, 13107u);
  EXPECT_EQ(sr.blocks[1].cumulative_lost, -3) << "24-bit signed";
  ASSERT_EQ(c.cnames.size(), 1u);
  EXPECT_EQ(c.cnames[0].first, 0xCAFEBABEu);
  EXPECT_EQ(c.cnames[0].second, "robot1@inspect");
}

// Bytes as RFC 3550 6.4.2 lays them out, written by hand.
TEST(Rtcp, ReceiverReportWireBytes) {
  std::vector<uint8_t> d;
  const ReportBlock b{0x01020304, 0x40, 0x000105, 0x00010203, 0x11, 0x22334455, 0x00010000};
  appendReceiverReport(d, 0xA0B0C0D0, std::span(&b, 1));
  const std::vector<uint8_t> want = {0x81, 201, 0x00, 0x07, 0xA0, 0xB0, 0xC0, 0xD0,  // V=2 RC=1, RR, length 7
                                     0x01, 0x02, 0x03, 0x04, 0x40, 0x00, 0x01, 0x05,  // SSRC_1, fraction, cumulative
                                     0x00, 0x01, 0x02, 0x03, 0x00, 0x00, 0x00, 0x11,  // highest seq, jitter
                                     0x22, 0x33, 0x44, 0x55, 0x00, 0x01, 0x00, 0x00};  // LSR, DLSR
  EXPECT_EQ(d, want);
}

TEST(Rtcp, CumulativeLostIsClampedTo24Bits) {
  std::vector<uint8_t> d;
  const ReportBlock b{1, 0, 50000000, 0, 0, 0, 0};
  appendReceiverReport(d, 2, std::span(&b, 1));
  Compound c;
  ASSERT_EQ(parseCompound(d, c), RtcpError::kNone);
  EXPECT_EQ(c.receiver_reports.at(0).blocks.at(0).cumulative_lost, 0x7FFFFF);
}

TEST(Rtcp, NackPacksPidAndBitmaskAcrossTheWrap) {
  const std::vector<uint16_t> lost = {65534, 65535, 0, 3, 15, 16, 40, 40, 100};
  std::vector<uint8_t> d;
  appendNack(d, 0x1111, 0x2222, lost);
  // 65534 covers 65535..14 (65535, 0, 3); 15 covers 16; then 40; then 100.
  ASSERT_EQ(d.size(), 12u + 4u * 4u);
  EXPECT_EQ(d[0], 0x80 | kFmtGenericNack);
  EXPECT_EQ(d[1], kTransportFeedback);
  EXPECT_EQ(d[12], 0xFF);  // PID 65534
  EXPECT_EQ(d[13], 0xFE);
  EXPECT_EQ(d[14], 0x00);  // BLP: bits 0 (65535), 1 (0), 4 (3)
  EXPECT_EQ(d[15], 0x13);
  Compound c;
  ASSERT_EQ(parseCompound(d, c), RtcpError::kNone);
  ASSERT_EQ(c.nacks.size(), 1u);
  EXPECT_EQ(c.nacks[0].sender_ssrc, 0x1111u);
  EXPECT_EQ(c.nacks[0].media_ssrc, 0x2222u);
  const std::set<uint16_t> got(c.nacks[0].seqs.begin(), c.nacks[0].seqs.end());
  EXPECT_EQ(got, std::set<uint16_t>(lost.begin(), lost.end()));
  EXPECT_EQ(c.nacks[0].seqs.size(), got.size()) << "duplicates merged";
  std::vector<uint8_t> none;
  appendNack(none, 1, 2, {});
  EXPECT_TRUE(none.empty());
}

TEST(Rtcp, RandomNackSetsRoundTrip) {
  std::mt19937 rng(22);
  for (int trial = 0; trial < 200; ++trial) {
    std::set<uint16_t> want;
    const uint16_t base = static_cast<uint16_t>(rng());
    const int n = 1 + static_cast<int>(rng() % 60);
    for (int k = 0; k < n; ++k) want.insert(static_cast<uint16_t>(base + rng() % 300));
    const std::vector<uint16_t> v(want.begin(), want.end());
    std::vector<uint8_t> d;
    appendNack(d, 1, 2, v);
    Compound c;
    ASSERT_EQ(parseCompound(d, c), RtcpError::kNone);
    ASSERT_EQ(c.nacks.size(), 1u);
    EXPECT_EQ(std::set<uint16_t>(c.nacks[0].seqs.begin(), c.nacks[0].seqs.end()), want);
  }
}

TEST(Rtcp, PliByeAndUnknownTypesInOneCompound) {
  std::vector<uint8_t> d;
  const ReportBlock b{};
  appendReceiverReport(d, 7, std::span(&b, 0));
  appendPli(d, 7, 9);
  // An APP packet (204) and a PSFB of another format (FIR, 4): skipped, counted.
  d.insert(d.end(), {0x80, 204, 0x00, 0x02, 0, 0, 0, 7, 'a', 'b', 'c', 'd'});
  d.insert(d.end(), {0x84, 206, 0x00, 0x02, 0, 0, 0, 7, 0, 0, 0, 9});
  appendBye(d, 7);
  Compound c;
  ASSERT_EQ(parseCompound(d, c), RtcpError::kNone);
  ASSERT_EQ(c.plis.size(), 1u);
  EXPECT_EQ(c.plis[0].sender_ssrc, 7u);
  EXPECT_EQ(c.plis[0].media_ssrc, 9u);
  EXPECT_EQ(c.byes, std::vector<uint32_t>{7});
  EXPECT_EQ(c.unknown, 2u);
  // Reduced-size RTCP (RFC 5506): the PLI alone.
  std::vector<uint8_t> alone;
  appendPli(alone, 3, 4);
  Compound c2;
  EXPECT_EQ(parseCompound(alone, c2), RtcpError::kNone);
  EXPECT_EQ(c2.plis.size(), 1u);
}

TEST(Rtcp, MalformedDatagramsNameTheFault) {
  std::vector<uint8_t> good;
  const ReportBlock b{1, 2, 3, 4, 5, 6, 7};
  appendReceiverReport(good, 9, std::span(&b, 1));
  Compound c;
  EXPECT_EQ(parseCompound(std::span(good).first(3), c), RtcpError::kTooShort);
  auto v1 = good;
  v1[0] = 0x41;  // version 1
  EXPECT_EQ(parseCompound(v1, c), RtcpError::kBadVersion);
  auto len = good;
  len[3] = 0x20;  // length past the end
  EXPECT_EQ(parseCompound(len, c), RtcpError::kBadLength);
  auto count = good;
  count[0] = 0x82;  // two blocks announced, one present
  EXPECT_EQ(parseCompound(count, c), RtcpError::kBadCount);
  // Padding on the first of two packets.
  auto pad = good;
  pad[0] |= 0x20;
  appendBye(pad, 9);
  EXPECT_EQ(parseCompound(pad, c), RtcpError::kBadPadding);
  // A NACK whose FCI is missing.
  std::vector<uint8_t> nack = {0x81, 205, 0x00, 0x02, 0, 0, 0, 1, 0, 0, 0, 2};
  EXPECT_EQ(parseCompound(nack, c), RtcpError::kBadFeedback);
  // An SDES item running past its packet.
  std::vector<uint8_t> sdes = {0x81, 202, 0x00, 0x02, 0, 0, 0, 1, 1, 200, 'x', 0};
  EXPECT_EQ(parseCompound(sdes, c), RtcpError::kBadCount);
  for (auto e : {RtcpError::kTooShort, RtcpError::kBadVersion, RtcpError::kBadLength, RtcpError::kBadPadding,
                 RtcpError::kBadCount, RtcpError::kBadFeedback})
    EXPECT_STRNE(toString(e), "?");
}

// Every prefix and every single-byte corruption of a valid compound parses
// to an error or to packets, never past the datagram (ASan checks the reads).
TEST(Rtcp, PrefixesAndCorruptionsNeverReadPastTheEnd) {
  std::vector<uint8_t> d;
  const ReportBlock b{1, 2, 3, 4, 5, 6, 7};
  appendSenderReport(d, 9, {1, 2, 3, 4}, std::span(&b, 1));
  appendCname(d, 9, "cname");
  const std::vector<uint16_t> seqs{1, 2, 30};
  appendNack(d, 9, 10, seqs);
  appendPli(d, 9, 10);
  for (std::size_t n = 0; n <= d.size(); ++n) {
    Compound c;
    (void)parseCompound(std::span(d).first(n), c);
  }
  std::mt19937 rng(5);
  for (int k = 0; k < 2000; ++k) {
    auto e = d;
    e[rng() % e.size()] = static_cast<uint8_t>(rng());
    Compound c;
    (void)parseCompound(e, c);
  }
  SUCCEED();
}

TEST(Rtcp, NtpTimeAndRoundTrip) {
  // 2026-01-01T00:00:00.5Z = 1767225600.5 s after the Unix epoch.
  const uint64_t ntp = ntpFromUnixMicros(1767225600500000ULL);
  EXPECT_EQ(ntp >> 32, 1767225600ULL + 2208988800ULL);
  EXPECT_EQ(static_cast<uint32_t>(ntp), 0x80000000u);
  // An SR sent at T, answered after 200 ms with DLSR 200 ms, back at T + 250 ms: RTT 50 ms.
  const uint64_t t0 = 1767225600000000ULL;
  const uint32_t lsr = ntpMiddle(ntpFromUnixMicros(t0));
  const uint32_t dlsr = static_cast<uint32_t>(0.2 * 65536);
  const auto rtt = roundTripSeconds(ntpMiddle(ntpFromUnixMicros(t0 + 250000)), lsr, dlsr);
  ASSERT_TRUE(rtt.has_value());
  EXPECT_NEAR(*rtt, 0.050, 0.0001);
  EXPECT_FALSE(roundTripSeconds(12345, 0, 0).has_value()) << "no SR yet";
  EXPECT_FALSE(roundTripSeconds(lsr, lsr, dlsr).has_value()) << "negative";
}

TEST(ReceiverStats, LossFractionAndCumulativeAcrossTheWrap) {
  ReceiverStats s;
  uint16_t seq = 65000;  // wraps after 536 packets
  uint64_t t_us = 0;
  uint32_t ts = 0;
  int sent = 0;
  for (int k = 0; k < 2000; ++k, ++seq, t_us += 3333, ts += 300) {
    ++sent;
    if (k > 5 && k % 10 == 0) continue;  // every tenth lost (not during probation)
    s.onPacket(seq, ts, t_us);
  }
  EXPECT_EQ(s.extendedHighest(), 65536u + static_cast<uint16_t>(seq - 1));
  const auto r = s.report(0xABCD, t_us);
  // The first packet is probation (A.1); of the 1999 after it, 199 were lost.
  EXPECT_EQ(r.cumulative_lost, 199);
  EXPECT_NEAR(r.fraction_lost / 256.0, 0.10, 0.005);
  EXPECT_EQ(r.ssrc, 0xABCDu);
  // The next interval without loss: fraction 0, cumulative unchanged.
  for (int k = 0; k < 100; ++k, ++seq, t_us += 3333, ts += 300) s.onPacket(seq, ts, t_us);
  const auto r2 = s.report(0xABCD, t_us);
  EXPECT_EQ(r2.fraction_lost, 0);
  EXPECT_EQ(r2.cumulative_lost, 199);
}

TEST(ReceiverStats, DuplicatesMakeLossNegativeAndAJumpRestarts) {
  ReceiverStats s;
  for (uint16_t q = 10; q < 20; ++q) s.onPacket(q, q * 3000u, q * 33333ull);
  s.onPacket(15, 15 * 3000u, 20 * 33333ull);  // a duplicate
  EXPECT_EQ(s.cumulativeLost(), -1);
  // A jump of 20000: rejected once, accepted when the next follows it (a restarted sender).
  EXPECT_FALSE(s.onPacket(20000, 0, 21 * 33333ull));
  EXPECT_TRUE(s.onPacket(20001, 3000, 22 * 33333ull));
  EXPECT_EQ(s.extendedHighest(), 20001u);
  EXPECT_EQ(s.cumulativeLost(), 0);
}

TEST(ReceiverStats, JitterFollowsAppendixA8) {
  ReceiverStats steady;
  for (int k = 0; k < 500; ++k) steady.onPacket(static_cast<uint16_t>(k), k * 3000u, k * 33333ull + 5000);
  EXPECT_LT(steady.jitterSeconds(), 0.0001) << "constant transit: no jitter";
  // Transit alternating 0 / 20 ms: |D| = 20 ms every packet, J converges to 20 ms.
  ReceiverStats alt;
  for (int k = 0; k < 500; ++k)
    alt.onPacket(static_cast<uint16_t>(k), static_cast<uint32_t>(k * 3000), k * 33333ull + (k % 2 ? 20000 : 0));
  EXPECT_NEAR(alt.jitterSeconds(), 0.020, 0.001);
  EXPECT_NEAR(alt.report(1, 0).jitter, 1800u, 90u) << "RTP units at 90 kHz";
}

TEST(ReceiverStats, DelaySinceLastSenderReport) {
  ReceiverStats s;
  s.onPacket(1, 0, 0);
  s.onPacket(2, 3000, 33333);
  const uint64_t ntp = ntpFromUnixMicros(1767225600000000ULL);
  s.onSenderReport(ntp, 1000000);
  const auto r = s.report(5, 1500000);
  EXPECT_EQ(r.lsr, ntpMiddle(ntp));
  EXPECT_NEAR(r.dlsr / 65536.0, 0.5, 0.0001);
}
