// H.264 over RTP (RFC 6184): packetizer, reorder buffer and depacketizer on
// synthetic access units, with loss, reordering, duplicates and garbage.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "shared/video/rtp_h264.hpp"

using namespace inspect::video;

namespace {

// A NAL unit of `size` bytes (header included) of the given type; the body
// never holds 00 00 0x (emulation prevention keeps real streams like that).
std::vector<uint8_t> nal(uint8_t type, std::size_t size, std::mt19937& rng) {
  std::vector<uint8_t> n(size);
  n[0] = static_cast<uint8_t>(0x60 | type);
  std::uniform_int_distribution<int> byte(1, 255);
  for (std::size_t i = 1; i < size; ++i) n[i] = static_cast<uint8_t>(byte(rng));
  return n;
}

std::vector<uint8_t> annexB(const std::vector<std::vector<uint8_t>>& nals, bool short_codes = false) {
  std::vector<uint8_t> out;
  for (const auto& n : nals) {
    if (!short_codes) out.push_back(0);
    out.insert(out.end(), {0, 0, 1});
    out.insert(out.end(), n.begin(), n.end());
  }
  return out;
}

struct Stream {
  std::vector<std::vector<uint8_t>> frames;  // Annex B with 4-byte start codes, as the depacketizer rebuilds them
  std::vector<bool> key;
};

// 30 frames: an IDR with SPS/PPS every 10, P frames of varied sizes.
Stream makeStream(std::mt19937& rng) {
  Stream s;
  std::uniform_int_distribution<std::size_t> psize(20, 9000);
  for (int f = 0; f < 30; ++f) {
    std::vector<std::vector<uint8_t>> nals;
    const bool key = f % 10 == 0;
    if (key) {
      nals.push_back(nal(kNalSps, 12, rng));
      nals.push_back(nal(kNalPps, 5, rng));
      nals.push_back(nal(kNalIdr, 14000, rng));
    } else {
      nals.push_back(nal(kNalSlice, psize(rng), rng));
    }
    s.frames.push_back(annexB(nals));
    s.key.push_back(key);
  }
  return s;
}

std::vector<std::vector<uint8_t>> packetizeAll(const Stream& s, H264Packetizer& pz) {
  std::vector<std::vector<uint8_t>> pkts;
  for (std::size_t f = 0; f < s.frames.size(); ++f)
    pz.packetize(s.frames[f], static_cast<uint32_t>(3000 * f), 1'000'000 + 33'333 * f, pkts);
  return pkts;
}

// Packetizes every frame (timestamp 3000 f, capture time f) and notes each packet's frame.
std::vector<std::vector<uint8_t>> packetizeTracked(const Stream& s, H264Packetizer& pz,
                                                  std::vector<std::size_t>& frame_of) {
  std::vector<std::vector<uint8_t>> pkts;
  for (std::size_t f = 0; f < s.frames.size(); ++f) {
    const std::size_t n = pz.packetize(s.frames[f], static_cast<uint32_t>(3000 * f), f, pkts);
    frame_of.insert(frame_of.end(), n, f);
  }
  return pkts;
}

struct Received {
  std::vector<Frame> frames;
  std::vector<bool> need_after;  // needKeyframe() just after each frame came out
  ReorderBuffer rb{16};
  H264Depacketizer dp;
  void feed(const std::vector<uint8_t>& d) {
    RtpPacket p;
    ASSERT_EQ(parseRtp(d, p), RtpError::kNone);
    rb.push(p.seq, d);
    drain(false);
  }
  void drain(bool flush) {
    std::vector<std::pair<uint32_t, std::vector<uint8_t>>> ready;
    if (flush) rb.flush(ready); else rb.pop(ready);
    for (auto& [skipped, datagram] : ready) {
      RtpPacket p;
      ASSERT_EQ(parseRtp(datagram, p), RtpError::kNone);
      if (auto f = dp.push(p, skipped)) {
        frames.push_back(std::move(*f));
        need_after.push_back(dp.needKeyframe());
      }
    }
  }
};

}  // namespace

TEST(AnnexB, SplitsOnThreeAndFourByteStartCodes) {
  const std::vector<uint8_t> b = {0, 0, 0, 1, 0x67, 1, 2, 0, 0, 1, 0x68, 3, 0, 0, 0, 0, 1, 0x65, 4, 5, 0};
  const auto n = splitAnnexB(b);
  ASSERT_EQ(n.size(), 3u);
  EXPECT_EQ(std::vector<uint8_t>(n[0].begin(), n[0].end()), (std::vector<uint8_t>{0x67, 1, 2}));
  EXPECT_EQ(std::vector<uint8_t>(n[1].begin(), n[1].end()), (std::vector<uint8_t>{0x68, 3}));
  EXPECT_EQ(std::vector<uint8_t>(n[2].begin(), n[2].end()), (std::vector<uint8_t>{0x65, 4, 5}));
  EXPECT_TRUE(splitAnnexB(std::vector<uint8_t>{0, 0, 0}).empty());
}

TEST(RtpH264, RoundTripKeepsEveryFrameAndItsCaptureTime) {
  std::mt19937 rng(1);
  const Stream s = makeStream(rng);
  H264Packetizer pz(0x1234abcd, 1200 - 28 - 12, 65500);  // MTU 1200: IP+UDP 28, RTP 12; seq wraps
  const auto pkts = packetizeAll(s, pz);
  Received r;
  int markers = 0;
  for (const auto& d : pkts) {
    EXPECT_LE(d.size(), 1200u - 28u) << "datagram over the MTU";
    RtpPacket p;
    ASSERT_EQ(parseRtp(d, p), RtpError::kNone);
    EXPECT_EQ(p.payload_type, kPayloadType);
    EXPECT_EQ(p.ssrc, 0x1234abcdu);
    markers += p.marker ? 1 : 0;
    r.feed(d);
  }
  r.drain(true);
  EXPECT_EQ(markers, 30);
  ASSERT_EQ(r.frames.size(), s.frames.size());
  for (std::size_t f = 0; f < s.frames.size(); ++f) {
    EXPECT_EQ(r.frames[f].annexb, s.frames[f]) << "frame " << f;
    EXPECT_EQ(r.frames[f].keyframe, s.key[f]);
    EXPECT_EQ(r.frames[f].has_parameter_sets, s.key[f]);
    ASSERT_TRUE(r.frames[f].capture_us.has_value());
    EXPECT_EQ(*r.frames[f].capture_us, 1'000'000 + 33'333 * f);
    EXPECT_EQ(r.frames[f].timestamp, 3000 * f);
  }
  EXPECT_EQ(r.dp.counters().frames_dropped, 0u);
  EXPECT_EQ(r.dp.counters().lost_packets, 0u);
  EXPECT_FALSE(r.dp.needKeyframe());
}

TEST(RtpH264, ReorderedAndDuplicatedPacketsStillMakeWholeFrames) {
  std::mt19937 rng(2);
  const Stream s = makeStream(rng);
  H264Packetizer pz(7, 1000);
  auto pkts = packetizeAll(s, pz);
  // Swap neighbours within windows of 6 and duplicate every 7th packet.
  // (Not the first window: the receiver anchors on the first packet it gets.)
  for (std::size_t i = 6; i + 6 <= pkts.size(); i += 6) std::shuffle(pkts.begin() + i, pkts.begin() + i + 6, rng);
  std::vector<std::vector<uint8_t>> sent;
  for (std::size_t i = 0; i < pkts.size(); ++i) {
    sent.push_back(pkts[i]);
    if (i % 7 == 3) sent.push_back(pkts[i]);
  }
  Received r;
  for (const auto& d : sent) r.feed(d);
  r.drain(true);
  ASSERT_EQ(r.frames.size(), s.frames.size());
  for (std::size_t f = 0; f < s.frames.size(); ++f) EXPECT_EQ(r.frames[f].annexb, s.frames[f]);
  EXPECT_GT(r.rb.duplicates() + r.rb.late(), 0u);
  EXPECT_EQ(r.dp.counters().frames_dropped, 0u);
}

TEST(RtpH264, ALostPacketDropsItsFrameAndAsksForAKeyframeUntilOneArrives) {
  std::mt19937 rng(3);
  const Stream s = makeStream(rng);
  H264Packetizer pz(9, 1100);
  std::vector<std::size_t> frame_of;
  const auto pkts = packetizeTracked(s, pz, frame_of);
  // Lose the middle packet of the first P frame after frame 10 that has at least 3 packets.
  std::size_t lost = 0, victim = 0;
  for (std::size_t f = 11; f < 20 && !victim; ++f) {
    const auto first = std::find(frame_of.begin(), frame_of.end(), f) - frame_of.begin();
    const auto n = std::count(frame_of.begin(), frame_of.end(), f);
    if (n >= 3) {
      victim = f;
      lost = static_cast<std::size_t>(first + n / 2);
    }
  }
  ASSERT_NE(victim, 0u) << "no P frame of 3+ packets";
  Received r;
  for (std::size_t i = 0; i < pkts.size(); ++i)
    if (i != lost) r.feed(pkts[i]);
  r.drain(true);
  bool asked_after_loss = false, cleared_at_20 = false;
  for (std::size_t k = 0; k < r.frames.size(); ++k) {
    if (r.frames[k].timestamp == 3000 * (victim + 1)) asked_after_loss = r.need_after[k];
    if (r.frames[k].timestamp == 3000 * 20) cleared_at_20 = !r.need_after[k];
  }
  EXPECT_EQ(r.frames.size(), s.frames.size() - 1);
  for (const auto& f : r.frames) EXPECT_NE(f.timestamp, 3000u * victim) << "the damaged frame was passed on";
  EXPECT_EQ(r.dp.counters().frames_dropped, 1u);
  EXPECT_EQ(r.dp.counters().lost_packets, 1u);
  EXPECT_TRUE(asked_after_loss);
  EXPECT_TRUE(cleared_at_20) << "the IDR at frame 20 clears the request";
}

TEST(RtpH264, StapAIsUnderstoodOnReceive) {
  // STAP-A with SPS, PPS and a small IDR in one packet (RFC 6184 5.7.1).
  const std::vector<uint8_t> sps = {0x67, 1, 2, 3}, pps = {0x68, 4}, idr = {0x65, 9, 9, 9, 9};
  std::vector<uint8_t> d = {0x80, 0x80 | kPayloadType, 0, 1, 0, 0, 0, 50, 0, 0, 0, 5, 0x78};
  for (const auto* n : {&sps, &pps, &idr}) {
    d.push_back(0);
    d.push_back(static_cast<uint8_t>(n->size()));
    d.insert(d.end(), n->begin(), n->end());
  }
  RtpPacket p;
  ASSERT_EQ(parseRtp(d, p), RtpError::kNone);
  H264Depacketizer dp;
  const auto f = dp.push(p, 0);
  ASSERT_TRUE(f.has_value());
  EXPECT_TRUE(f->keyframe);
  EXPECT_TRUE(f->has_parameter_sets);
  EXPECT_EQ(f->annexb, annexB({sps, pps, idr}));
}

TEST(RtpH264, AStartCodeInsideANalUnitDropsItsFrame) {
  // H.264 7.4.1 forbids 00 00 00/01/02 inside a NAL unit and a last byte 00:
  // a decoder would cut such a unit into others than the depacketizer saw (a
  // P slice carrying "00 00 01 65" would decode as an IDR). Found by fuzz_rtp_h264.
  auto packet = [](uint16_t seq, std::vector<uint8_t> payload, bool marker) {
    std::vector<uint8_t> d = {0x80, static_cast<uint8_t>((marker ? 0x80 : 0) | kPayloadType), 0,
                              static_cast<uint8_t>(seq), 0, 0, 0, 50, 0, 0, 0, 5};
    d.insert(d.end(), payload.begin(), payload.end());
    return d;
  };
  const std::vector<std::vector<uint8_t>> bad = {
      {0x41, 0xFF, 0, 0, 1, 0x65, 0x88},  // a start code, then an IDR header
      {0x41, 7, 0, 0, 0, 9},              // 00 00 00
      {0x41, 7, 0, 0, 2, 9},              // 00 00 02
      {0x41, 7, 9, 0},                    // last byte 00
  };
  for (const auto& b : bad) {
    H264Depacketizer dp;
    RtpPacket p;
    const auto d = packet(1, b, true);
    ASSERT_EQ(parseRtp(d, p), RtpError::kNone);
    EXPECT_FALSE(dp.push(p, 0).has_value());
    EXPECT_EQ(dp.counters().bad_payload, 1u);
    EXPECT_EQ(dp.counters().frames_dropped, 1u);
  }
  // Emulation prevention (00 00 03) is fine; a start code split across two FU-A fragments is not.
  H264Depacketizer dp;
  RtpPacket p;
  auto d = packet(1, {0x41, 7, 0, 0, 3, 1, 9}, true);
  ASSERT_EQ(parseRtp(d, p), RtpError::kNone);
  EXPECT_TRUE(dp.push(p, 0).has_value());
  const auto a = packet(2, {0x7C, 0x81, 7, 0}, false), b = packet(3, {0x7C, 0x41, 0, 1, 0x65, 9}, true);
  ASSERT_EQ(parseRtp(a, p), RtpError::kNone);
  EXPECT_FALSE(dp.push(p, 0).has_value());
  ASSERT_EQ(parseRtp(b, p), RtpError::kNone);
  EXPECT_FALSE(dp.push(p, 0).has_value());
  EXPECT_EQ(dp.counters().bad_payload, 1u);
  EXPECT_EQ(dp.counters().frames, 1u);
}

TEST(ReorderBuffer, SkipGapGivesUpTheFirstGapOnlyAndKeepsWaitingForTheNext) {
  ReorderBuffer rb(1024);
  std::vector<std::pair<uint32_t, std::vector<uint8_t>>> out;
  for (uint16_t q : {65534, 1, 2, 4}) rb.push(q, std::vector<uint8_t>{static_cast<uint8_t>(q)});  // 65535, 0, 3 missing
  rb.pop(out);
  ASSERT_EQ(out.size(), 1u);  // 65534
  out.clear();
  rb.skipGap(out);  // gives up 65535 and 0: releases 1, 2
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].first, 2u) << "two skipped before it";
  EXPECT_EQ(out[0].second[0], 1);
  EXPECT_EQ(out[1].first, 0u);
  EXPECT_EQ(rb.next(), 3);
  EXPECT_EQ(rb.held(), 1u) << "4 still waits for 3";
  out.clear();
  rb.push(3, {3});
  rb.pop(out);
  EXPECT_EQ(out.size(), 2u);
  EXPECT_EQ(rb.held(), 0u);
}

TEST(RtpH264, BadHeadersAreNamed) {
  RtpPacket p;
  EXPECT_EQ(parseRtp(std::vector<uint8_t>(5, 0x80), p), RtpError::kTooShort);
  EXPECT_EQ(parseRtp(std::vector<uint8_t>(20, 0x40), p), RtpError::kBadVersion);
  std::vector<uint8_t> csrc(14, 0);
  csrc[0] = 0x8F;  // 15 CSRCs announced
  EXPECT_EQ(parseRtp(csrc, p), RtpError::kBadCsrc);
  std::vector<uint8_t> ext = {0x90, 96, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0xBE, 0xDE, 0, 9, 0x17};
  EXPECT_EQ(parseRtp(ext, p), RtpError::kBadExtension);
  std::vector<uint8_t> pad = {0xA0, 96, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0x41, 200};
  EXPECT_EQ(parseRtp(pad, p), RtpError::kBadPadding);
  EXPECT_STREQ(toString(RtpError::kBadPadding), "padding longer than the payload");
}

TEST(RtpH264, GarbageNeverCrashesAndIsCounted) {
  std::mt19937 rng(4);
  std::uniform_int_distribution<int> len(0, 1500), byte(0, 255);
  H264Depacketizer dp;
  ReorderBuffer rb(8);
  uint64_t parsed = 0;
  for (int i = 0; i < 20000; ++i) {
    std::vector<uint8_t> d(static_cast<std::size_t>(len(rng)));
    for (auto& b : d) b = static_cast<uint8_t>(byte(rng));
    if (i % 2 && !d.empty()) d[0] = static_cast<uint8_t>(0x80 | (d[0] & 0x3F));  // half of them look like RTP v2
    RtpPacket p;
    if (parseRtp(d, p) != RtpError::kNone) continue;
    ++parsed;
    rb.push(p.seq, d);
    std::vector<std::pair<uint32_t, std::vector<uint8_t>>> ready;
    rb.pop(ready);
    for (auto& [skipped, datagram] : ready) {
      RtpPacket q;
      if (parseRtp(datagram, q) == RtpError::kNone) (void)dp.push(q, skipped);
    }
  }
  EXPECT_GT(parsed, 1000u);
  EXPECT_GT(dp.counters().bad_payload + dp.counters().frames_dropped, 0u);
}

TEST(RtpH264, AWholeLostFrameCostsOnlyThatFrame) {
  std::mt19937 rng(5);
  const Stream s = makeStream(rng);
  H264Packetizer pz(11, 1100);
  std::vector<std::size_t> frame_of;
  const auto pkts = packetizeTracked(s, pz, frame_of);
  Received r;
  for (std::size_t i = 0; i < pkts.size(); ++i)
    if (frame_of[i] != 5) r.feed(pkts[i]);  // every packet of frame 5 lost
  r.drain(true);
  EXPECT_EQ(r.frames.size(), s.frames.size() - 1);
  EXPECT_EQ(r.dp.counters().frames_dropped, 0u);  // nothing partial reached the depacketizer
  EXPECT_GT(r.dp.counters().lost_packets, 0u);
  EXPECT_FALSE(r.dp.needKeyframe()) << "the IDR at frame 10 cleared it";
}
