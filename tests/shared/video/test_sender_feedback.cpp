// The robot's sender answering RTCP over real loopback UDP (rtcp-mux): a
// NACK gets RFC 4588 RTX packets that unwrap to the very datagrams sent, a
// PLI gets a keyframe, a receiver report gives the RTT, and a sender report
// arrives every second. The test plays the receiver with a plain socket.
#include <gtest/gtest.h>

#include <chrono>
#include <algorithm>
#include <map>
#include <optional>
#include <thread>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>
#include <poll.h>

#include "shared/util/clock.hpp"
#include "shared/video/h264_codec.hpp"
#include "shared/video/rtcp.hpp"
#include "shared/video/rtp_h264.hpp"
#include "shared/video/rtx.hpp"
#include "shared/video/video_sender.hpp"

using namespace inspect;
using namespace inspect::video;
namespace asio = boost::asio;

namespace {

struct Peer {
  asio::io_context io;
  asio::ip::udp::socket sock{io, asio::ip::udp::endpoint(asio::ip::make_address("127.0.0.1"), 0)};
  asio::ip::udp::endpoint sender;
  uint16_t port() const { return sock.local_endpoint().port(); }
  // One datagram, or empty after the 100 ms timeout.
  std::vector<uint8_t> read() {
    pollfd pfd{sock.native_handle(), POLLIN, 0};
    if (::poll(&pfd, 1, 100) <= 0) return {};
    std::vector<uint8_t> b(4096);
    boost::system::error_code ec;
    const std::size_t n = sock.receive_from(asio::buffer(b), sender, 0, ec);
    if (ec) return {};
    b.resize(n);
    return b;
  }
  void send(const std::vector<uint8_t>& d) { sock.send_to(asio::buffer(d), sender); }
};

SenderSettings settings(uint16_t port) {
  SenderSettings s;
  s.source.width = 160;
  s.source.height = 120;
  s.source.fps = 30;
  s.encoder.gop = 300;  // no periodic keyframe within the test
  s.encoder.bitrate_kbps = 300;
  s.host = "127.0.0.1";
  s.port = port;
  return s;
}

}  // namespace

TEST(SenderFeedback, NackPliReportsAndSenderReports) {
  Peer peer;
  VideoSender tx(settings(peer.port()));
  tx.start();
  std::map<uint16_t, std::vector<uint8_t>> media;
  std::vector<rtcp::SenderReport> srs;
  std::vector<std::string> cnames;
  std::map<uint16_t, std::vector<uint8_t>> rtx;  // by original sequence number
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  bool nacked = false, pli_sent = false, rr_sent = false;
  std::vector<uint16_t> asked;
  uint64_t keyframes_before_pli = 0;
  for (int k = 0; k < 2000 && std::chrono::steady_clock::now() < deadline; ++k) {
    const auto d = peer.read();
    if (d.empty()) continue;
    if (rtcp::looksLikeRtcp(d)) {
      rtcp::Compound c;
      ASSERT_EQ(rtcp::parseCompound(d, c), rtcp::RtcpError::kNone);
      for (auto& sr : c.sender_reports) srs.push_back(sr);
      for (auto& [ssrc, name] : c.cnames) cnames.push_back(name);
    } else {
      RtpPacket p;
      ASSERT_EQ(parseRtp(d, p), RtpError::kNone);
      if (p.payload_type == kPayloadType) {
        EXPECT_EQ(p.ssrc, tx.ssrc());
        media[p.seq] = d;
      } else {
        ASSERT_EQ(p.payload_type, kRtxPayloadType);
        EXPECT_EQ(p.ssrc, tx.stats().rtx_ssrc);
        std::vector<uint8_t> orig;
        ASSERT_EQ(unwrapRtx(d, kRtxPayloadType, kPayloadType, tx.ssrc(), orig), RtxError::kNone);
        rtx[static_cast<uint16_t>(orig[2] << 8 | orig[3])] = orig;
      }
    }
    if (!nacked && media.size() >= 20) {
      // Ask for three packets we did get (so we can compare) and one never sent.
      auto it = media.begin();
      for (int j = 0; j < 3; ++j, ++it) asked.push_back(it->first);
      asked.push_back(static_cast<uint16_t>(media.rbegin()->first + 30000));
      std::vector<uint8_t> fb;
      rtcp::appendNack(fb, 0x5E55, tx.ssrc(), asked);
      peer.send(fb);
      nacked = true;
    }
    if (!pli_sent && rtx.size() >= 3) {
      keyframes_before_pli = tx.stats().keyframes;
      std::vector<uint8_t> fb;
      rtcp::appendPli(fb, 0x5E55, tx.ssrc());
      peer.send(fb);
      pli_sent = true;
    }
    if (!rr_sent && !srs.empty()) {
      // A receiver report about the stream 20 ms after its SR (DLSR), 10 % lost.
      rtcp::ReportBlock b;
      b.ssrc = tx.ssrc();
      b.fraction_lost = 26;
      b.lsr = rtcp::ntpMiddle(srs.back().info.ntp);
      b.dlsr = static_cast<uint32_t>(0.020 * 65536);
      std::vector<uint8_t> fb;
      rtcp::appendReceiverReport(fb, 0x5E55, std::span(&b, 1));
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      peer.send(fb);
      rr_sent = true;
    }
    if (rr_sent && pli_sent && srs.size() >= 2 && tx.stats().keyframes > keyframes_before_pli &&
        tx.stats().rtt_ms >= 0)
      break;
  }
  tx.stop();
  const SenderStats st = tx.stats();
  ASSERT_TRUE(nacked);
  ASSERT_EQ(rtx.size(), 3u) << "three of the four asked for were held";
  for (const auto& [seq, orig] : rtx) EXPECT_EQ(orig, media.at(seq)) << "seq " << seq;
  EXPECT_EQ(st.nacks, 1u);
  EXPECT_EQ(st.nacked_packets, 4u);
  EXPECT_EQ(st.retransmitted, 3u);
  EXPECT_EQ(st.not_in_history, 1u);
  EXPECT_EQ(st.plis, 1u);
  EXPECT_GT(st.keyframes, keyframes_before_pli) << "the PLI gave a keyframe";
  ASSERT_GE(srs.size(), 2u) << "a sender report every second";
  EXPECT_EQ(srs[0].ssrc, tx.ssrc());
  EXPECT_GT(srs.back().info.packets, 0u);
  ASSERT_FALSE(cnames.empty());
  EXPECT_EQ(st.receiver_reports, 1u);
  EXPECT_NEAR(st.peer_loss_pct, 10.0, 0.5);
  EXPECT_GE(st.rtt_ms, 0.0);
  EXPECT_LT(st.rtt_ms, 50.0) << "loopback: the 20 ms the test held the report are DLSR, not RTT";
}

TEST(SenderFeedback, GarbageOnTheFeedbackPathIsCountedNotFatal) {
  Peer peer;
  VideoSender tx(settings(peer.port()));
  tx.start();
  for (int k = 0; k < 50 && peer.read().empty(); ++k) {
  }
  peer.send({0x80, 205, 0xFF, 0xFF, 1, 2});  // RTCP type, length past the end
  peer.send({0x81, 205, 0x00, 0x02, 0, 0, 0, 1, 0, 0, 0, 2});  // a NACK without FCI
  peer.send({1, 2, 3});                                         // not RTCP at all
  for (int k = 0; k < 50 && tx.stats().rtcp_errors < 3; ++k) peer.read();
  tx.stop();
  EXPECT_EQ(tx.stats().rtcp_errors, 3u);
  EXPECT_NE(tx.stats().error.find("RTCP"), std::string::npos);
  EXPECT_EQ(tx.stats().retransmitted, 0u);
}

// Rate adaptation end to end on the real sender: receiver reports of heavy
// loss lower the bitrate in place (no keyframe), then halve the frame rate,
// then the size (each a new IDR); clean reports bring back the size first,
// then the frame rate. The stream is depacketized and decoded to see it.
TEST(SenderFeedback, ReportsOfHeavyLossLowerTheRateThenTheFrameRateThenTheSizeAndCleanOnesUndoIt) {
  Peer peer;
  SenderSettings s = settings(peer.port());
  s.source.width = 320;
  s.source.height = 240;
  s.encoder.bitrate_kbps = 1000;
  s.adapt.min_kbps = 300;
  s.adapt.level_hold_s = 0.3;
  s.adapt.increase_per_s = 2.0;  // a fast climb back, so that the test is short
  VideoSender tx(s);
  tx.start();
  H264Depacketizer depack;
  H264Decoder dec;
  struct Seen {
    int level;
    int width;
    bool keyframe;
    uint32_t ts;
  };
  std::vector<Seen> frames;
  std::vector<std::pair<int, int>> rates;  // (kbps, level) after each report
  std::vector<std::string> reasons;
  std::optional<uint16_t> last_seq;
  auto next_report = std::chrono::steady_clock::now() + std::chrono::milliseconds(300);
  int reports = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(15);
  bool clean_phase = false, done = false;
  for (int k = 0; k < 20000 && !done && std::chrono::steady_clock::now() < deadline; ++k) {
    const auto d = peer.read();
    if (!d.empty() && !rtcp::looksLikeRtcp(d)) {
      RtpPacket p;
      ASSERT_EQ(parseRtp(d, p), RtpError::kNone);
      if (p.payload_type != kPayloadType) continue;
      const uint32_t skipped = last_seq ? static_cast<uint16_t>(p.seq - *last_seq - 1) : 0;
      last_seq = p.seq;
      if (auto f = depack.push(p, skipped)) {
        cv::Mat bgr;
        if (dec.decode(f->annexb.data(), f->annexb.size(), bgr))
          frames.push_back({tx.stats().rate_level, bgr.cols, f->keyframe, f->timestamp});
      }
    }
    if (std::chrono::steady_clock::now() < next_report) continue;
    next_report += std::chrono::milliseconds(100);
    rtcp::ReportBlock b;
    b.ssrc = tx.ssrc();
    b.fraction_lost = clean_phase ? 0 : 102;  // 40 %: x0.8 a report
    std::vector<uint8_t> fb;
    rtcp::appendReceiverReport(fb, 0x5E55, std::span(&b, 1));
    peer.send(fb);
    ++reports;
    // Sample once the sender has taken this report in (under the sanitizers
    // its feedback thread can be late by more than a report interval, and a
    // state sampled twice-removed loses a reason).
    SenderStats st = tx.stats();
    for (int w = 0; w < 500 && st.receiver_reports < static_cast<uint64_t>(reports); ++w) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      st = tx.stats();
    }
    rates.emplace_back(st.rate_kbps, st.rate_level);
    if (reasons.empty() || reasons.back() != st.rate_reason) reasons.push_back(st.rate_reason);
    if (!clean_phase && st.rate_level == 2) {
      // Stay a while at the lowest level, then the link is clean again.
      if (std::count_if(rates.begin(), rates.end(), [](auto r) { return r.second == 2; }) >= 8) clean_phase = true;
    } else if (clean_phase && st.rate_level == 0 && st.rate_kbps >= 600) {
      done = true;
    }
  }
  tx.stop();
  const SenderStats st = tx.stats();
  ASSERT_TRUE(done) << "level " << st.rate_level << " rate " << st.rate_kbps << " after " << reports << " reports";
  // The rate fell x0.8 a report while it stayed at full frame rate and size: 1000, 801, 641, 513, 411, 329.
  ASSERT_GE(rates.size(), 6u);
  EXPECT_EQ(rates[0], std::make_pair(801, 0));  // 102/256 lost: x0.8008
  EXPECT_EQ(rates[4], std::make_pair(329, 0));
  // Levels went 0 -> 1 -> 2 -> 1 -> 0, one step at a time.
  std::vector<int> levels;
  for (const auto& [kbps, level] : rates) {
    EXPECT_GE(kbps, 300);
    if (levels.empty() || levels.back() != level) levels.push_back(level);
  }
  EXPECT_EQ(levels, (std::vector<int>{0, 1, 2, 1, 0}));
  // What was decoded: full size at levels 0 and 1, half at level 2; no
  // keyframe for an in-place rate change, one for each level change.
  int keyframes_at_level0_before_any_step = 0, small = 0, big_at_2 = 0;
  bool stepped = false;
  for (const auto& f : frames) {
    stepped = stepped || f.level > 0;
    if (!stepped && f.keyframe) ++keyframes_at_level0_before_any_step;
    if (f.width == 160) ++small;
    if (f.level == 2 && f.width == 320) ++big_at_2;
  }
  EXPECT_EQ(keyframes_at_level0_before_any_step, 1) << "only the first frame: rate changes are in place";
  EXPECT_GT(small, 5);
  EXPECT_LT(big_at_2, 3) << "frames in flight when the level changed";
  EXPECT_GE(st.keyframes, 5u) << "the first, and one per level change";
  EXPECT_GT(st.rate_skipped, 10u) << "half the frame rate at levels 1 and 2";
  EXPECT_EQ(dec.counters().errors, 0u);
  const auto said = [&](const char* what) {
    return std::any_of(reasons.begin(), reasons.end(), [&](const std::string& r) { return r.find(what) != r.npos; });
  };
  EXPECT_TRUE(said("loss 39.8 % > 10 %: x0.80; below 300 kbit/s: frame rate halved"));
  EXPECT_TRUE(said("size halved"));
  EXPECT_TRUE(said("size restored"));
  EXPECT_TRUE(said("frame rate restored"));
}
