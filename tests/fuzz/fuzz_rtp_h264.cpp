// Fuzzes the server's video receive path without a socket: RTP parsing,
// the reorder buffer, the H.264 depacketizer (shared/video/rtp_h264) and the
// real libavcodec decoder (shared/video/h264_codec), with what
// VideoReceiver does between them (SPS/PPS kept for the SDP file, frames
// skipped until a keyframe after a loss).
//
// Input: records (fuzz_records.hpp). tag % 8 == 7 flushes the reorder buffer
// (a pause); tag % 8 == 6 is an RTCP datagram (shared/video/rtcp: reports,
// NACK, PLI; what it parses to is rebuilt by the builders and parses back
// the same; its report blocks drive the robot's rate adaptation, which stays
// within its range and levels); any other record is one RTP datagram (also wrapped as RFC 4588
// RTX and unwrapped: the same bytes). tag bit 3 picks the BGR
// or the luma-only decode for the frames it completes; RTP records also feed
// the NACK list and a sender's retransmission history (tag bit 4: a tail probe).
// Invariants: frames hold Annex B NAL units; a frame re-packetized by the
// robot's packetizer (small and normal MTU) comes out of a fresh
// depacketizer with the same NAL units.
#include <cstddef>
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "shared/util/log.hpp"
#include "shared/video/h264_codec.hpp"
#include "shared/video/rate_controller.hpp"
#include "shared/video/rtcp.hpp"
#include "shared/video/rtp_h264.hpp"
#include "shared/video/rtx.hpp"
#include "shared/video/sdp.hpp"
#include "tests/fuzz/fuzz_records.hpp"

using namespace inspect;
using namespace inspect::video;

namespace {

bool singleNalTypes(const std::vector<std::span<const uint8_t>>& nals) {
  for (const auto& n : nals)
    if (nalType(n[0]) < 1 || nalType(n[0]) > 23) return false;
  return true;
}

// The robot's packetizer and a fresh depacketizer give the frame's NAL units back.
void checkRoundTrip(const Frame& f, std::size_t max_payload) {
  const auto nals = splitAnnexB(f.annexb);
  if (nals.empty() || !singleNalTypes(nals)) return;
  H264Packetizer pk(0x1234, max_payload, 65000);
  std::vector<std::vector<uint8_t>> packets;
  pk.packetize(f.annexb, f.timestamp, 42, packets);
  H264Depacketizer dp;
  std::optional<Frame> out;
  for (std::size_t i = 0; i < packets.size(); ++i) {
    RtpPacket p;
    FUZZ_CHECK(parseRtp(packets[i], p) == RtpError::kNone);
    FUZZ_CHECK(p.payload.size() <= max_payload);
    FUZZ_CHECK(p.marker == (i + 1 == packets.size()));
    FUZZ_CHECK(p.capture_us.has_value() == (i == 0));
    auto got = dp.push(p, 0);
    FUZZ_CHECK(got.has_value() == (i + 1 == packets.size()));
    if (got) out = std::move(got);
  }
  FUZZ_CHECK(out.has_value());
  const auto back = splitAnnexB(out->annexb);
  FUZZ_CHECK(back.size() == nals.size());
  for (std::size_t i = 0; i < nals.size(); ++i)
    FUZZ_CHECK(std::equal(nals[i].begin(), nals[i].end(), back[i].begin(), back[i].end()));
  FUZZ_CHECK(out->keyframe == f.keyframe);
}

bool sameBlocks(const std::vector<rtcp::ReportBlock>& a, const std::vector<rtcp::ReportBlock>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (a[k].ssrc != b[k].ssrc || a[k].fraction_lost != b[k].fraction_lost ||
        a[k].cumulative_lost != b[k].cumulative_lost || a[k].highest_seq != b[k].highest_seq ||
        a[k].jitter != b[k].jitter || a[k].lsr != b[k].lsr || a[k].dlsr != b[k].dlsr)
      return false;
  return true;
}

// An RTCP datagram: whatever parses is rebuilt and parses back the same.
// The robot's rate adaptation fed every report block: it stays in its range and levels.
void adapt(const rtcp::Compound& c, RateController& rate, uint64_t now_us) {
  const auto feed = [&](const std::vector<rtcp::ReportBlock>& blocks) {
    for (const auto& b : blocks) {
      rate.onReport(now_us, b.fraction_lost / 256.0,
                    b.dlsr % 3 == 0 ? std::nullopt : std::optional<double>((b.dlsr % 4096) / 8.0));
      rate.tick(now_us + b.lsr % 5'000'000);
      const RateState& st = rate.state();
      FUZZ_CHECK(st.kbps >= rate.settings().min_kbps && st.kbps <= rate.settings().max_kbps);
      FUZZ_CHECK(st.level >= 0 && st.level <= rate.settings().max_level);
      FUZZ_CHECK(!st.reason.empty());
    }
  };
  for (const auto& sr : c.sender_reports) feed(sr.blocks);
  for (const auto& rr : c.receiver_reports) feed(rr.blocks);
}

void checkRtcp(std::span<const uint8_t> d, rtcp::ReceiverStats& stats, RateController& rate, uint64_t now_us) {
  rtcp::Compound c;
  const rtcp::RtcpError e = rtcp::parseCompound(d, c);
  FUZZ_CHECK(std::string(rtcp::toString(e)) != "?");
  adapt(c, rate, now_us);
  std::vector<uint8_t> again;
  for (const auto& sr : c.sender_reports) {
    rtcp::appendSenderReport(again, sr.ssrc, sr.info, sr.blocks);
    stats.onSenderReport(sr.info.ntp, sr.info.ntp >> 12);
  }
  for (const auto& rr : c.receiver_reports) rtcp::appendReceiverReport(again, rr.ssrc, rr.blocks);
  for (const auto& [ssrc, cname] : c.cnames) rtcp::appendCname(again, ssrc, cname);
  for (uint32_t b : c.byes) rtcp::appendBye(again, b);
  for (const auto& n : c.nacks) rtcp::appendNack(again, n.sender_ssrc, n.media_ssrc, n.seqs);
  for (const auto& p : c.plis) rtcp::appendPli(again, p.sender_ssrc, p.media_ssrc);
  if (again.empty()) return;
  rtcp::Compound back;
  FUZZ_CHECK(rtcp::parseCompound(again, back) == rtcp::RtcpError::kNone);
  FUZZ_CHECK(back.sender_reports.size() == c.sender_reports.size());
  for (std::size_t k = 0; k < c.sender_reports.size(); ++k) {
    FUZZ_CHECK(back.sender_reports[k].info.ntp == c.sender_reports[k].info.ntp);
    FUZZ_CHECK(sameBlocks(back.sender_reports[k].blocks, c.sender_reports[k].blocks));
  }
  FUZZ_CHECK(back.receiver_reports.size() == c.receiver_reports.size());
  for (std::size_t k = 0; k < c.receiver_reports.size(); ++k)
    FUZZ_CHECK(sameBlocks(back.receiver_reports[k].blocks, c.receiver_reports[k].blocks));
  FUZZ_CHECK(back.cnames == c.cnames);
  FUZZ_CHECK(back.byes == c.byes);
  FUZZ_CHECK(back.nacks.size() == c.nacks.size());
  for (std::size_t k = 0; k < c.nacks.size(); ++k) {
    const std::set<uint16_t> want(c.nacks[k].seqs.begin(), c.nacks[k].seqs.end());
    FUZZ_CHECK(std::set<uint16_t>(back.nacks[k].seqs.begin(), back.nacks[k].seqs.end()) == want);
  }
  FUZZ_CHECK(back.plis.size() == c.plis.size());
}

struct Receiver {
  ReorderBuffer reorder{16};
  H264Depacketizer depack;
  H264Decoder decoder;
  std::vector<uint8_t> sps, pps;
  bool damaged = false;
  rtcp::ReceiverStats stats;
  RateController rate;
  std::vector<std::pair<uint32_t, std::vector<uint8_t>>> ready;
  // Repair: the receiver's NACK list fed every sequence number (tail probes
  // on tag bit 4), answered from a sender's history of the same datagrams.
  NackList nacks;
  RetransmissionHistory history{64, 1'000'000};
  uint64_t now_us = 0;

  void repair(uint16_t seq, std::span<const uint8_t> dgram, bool probe) {
    now_us += 1000;
    history.remember(seq, dgram, now_us);
    nacks.onPacket(seq, now_us);
    if (probe) (void)nacks.probeTail(now_us);
    for (uint16_t q : nacks.due(now_us, 20000)) {
      const auto plan = history.planRetransmission(q, now_us, 5000);
      FUZZ_CHECK(plan.copies >= 0 && plan.copies <= 2 && (plan.datagram != nullptr || plan.copies == 0));
    }
    (void)nacks.expire(now_us > 250000 ? now_us - 250000 : 0, now_us, 20000);
    (void)nacks.expireBefore(reorder.next());
    FUZZ_CHECK(nacks.size() <= NackSettings{}.max_missing);
    FUZZ_CHECK(!nacks.missing(static_cast<uint16_t>(reorder.next() - 1)));  // released: nothing left to ask for
  }

  void onFrame(const Frame& f, bool luma) {
    FUZZ_CHECK(f.annexb.size() >= 5);
    FUZZ_CHECK(f.annexb[0] == 0 && f.annexb[1] == 0 && f.annexb[2] == 0 && f.annexb[3] == 1);
    if (f.has_parameter_sets) {
      for (auto nal : splitAnnexB(f.annexb)) {
        if (nalType(nal[0]) == kNalSps) sps.assign(nal.begin(), nal.end());
        if (nalType(nal[0]) == kNalPps) pps.assign(nal.begin(), nal.end());
      }
      if (!sps.empty() && !pps.empty()) {
        SdpParams p;
        p.session_name = "fuzz camera";
        p.sps = sps;
        p.pps = pps;
        FUZZ_CHECK(!makeSdp(p).empty());
      }
    }
    checkRoundTrip(f, 64);
    checkRoundTrip(f, 1200 - 28 - kRtpHeaderSize);
    if (!f.keyframe && (damaged || depack.needKeyframe())) {
      damaged = true;
      return;
    }
    cv::Mat pic;
    const bool ok = luma ? decoder.decodeLuma(f.annexb.data(), f.annexb.size(), pic)
                         : decoder.decode(f.annexb.data(), f.annexb.size(), pic);
    if (!ok) {
      if (decoder.counters().errors > 0) damaged = true;
      return;
    }
    FUZZ_CHECK(!pic.empty() && pic.type() == (luma ? CV_8UC1 : CV_8UC3));
    if (f.keyframe) damaged = false;
  }

  void depacketizeReady(bool luma) {
    for (auto& [skipped, dgram] : ready) {
      RtpPacket p;
      if (parseRtp(dgram, p) != RtpError::kNone) continue;
      FUZZ_CHECK(p.payload.data() >= dgram.data() && p.payload.data() + p.payload.size() <= dgram.data() + dgram.size());
      const uint64_t dropped = depack.counters().frames_dropped;
      auto f = depack.push(p, skipped);
      if (depack.counters().frames_dropped != dropped) damaged = true;
      if (f) onFrame(*f, luma);
    }
    ready.clear();
  }
};

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  log::setLevel(log::Level::kError);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  Receiver rx;
  fuzz::RecordReader in(data, size);
  fuzz::Record r;
  while (in.next(r)) {
    const bool luma = r.tag & 0x08;
    if (r.tag % 8 == 7) {
      rx.reorder.flush(rx.ready);
    } else if (r.tag % 8 == 6) {
      checkRtcp(r.body, rx.stats, rx.rate, rx.now_us);
      (void)rx.stats.report(1, r.body.size());
    } else {
      RtpPacket p;
      const RtpError e = parseRtp(r.body, p);
      (void)toString(e);
      if (e != RtpError::kNone) continue;  // VideoReceiver counts and drops it
      if (!(r.body[0] & 0x20)) {  // RFC 4588: the RTX packet of an unpadded packet unwraps to it, byte for byte
        const auto rtx = makeRtx(r.body, 0xBEEF, kRtxPayloadType, static_cast<uint16_t>(p.seq + 7));
        FUZZ_CHECK(rtx.has_value());
        std::vector<uint8_t> back;
        FUZZ_CHECK(unwrapRtx(*rtx, kRtxPayloadType, p.payload_type, p.ssrc, back) == RtxError::kNone);
        FUZZ_CHECK(std::equal(back.begin(), back.end(), r.body.begin(), r.body.end()));
      }
      rx.stats.onPacket(p.seq, p.timestamp, p.capture_us.value_or(0));
      FUZZ_CHECK(rx.stats.report(p.ssrc, 0).fraction_lost <= 255);
      rx.reorder.push(p.seq, std::vector<uint8_t>(r.body.begin(), r.body.end()));
      rx.reorder.pop(rx.ready);
      rx.repair(p.seq, r.body, r.tag & 0x10);
    }
    FUZZ_CHECK(rx.reorder.held() <= 16);
    rx.depacketizeReady(luma);
  }
  rx.reorder.flush(rx.ready);
  rx.depacketizeReady(false);
  return 0;
}
