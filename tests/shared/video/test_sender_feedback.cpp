// The robot's sender answering RTCP over real loopback UDP (rtcp-mux): a
// NACK gets RFC 4588 RTX packets that unwrap to the very datagrams sent, a
// PLI gets a keyframe, a receiver report gives the RTT, and a sender report
// arrives every second. The test plays the receiver with a plain socket.
#include <gtest/gtest.h>

#include <chrono>
#include <map>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>
#include <poll.h>

#include "shared/util/clock.hpp"
#include "shared/video/rtcp.hpp"
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
