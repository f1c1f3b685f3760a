#include "shared/video/rtcp.hpp"

#include <algorithm>

#include "shared/video/byte_order.hpp"

namespace inspect::video::rtcp {
namespace {

constexpr uint32_t kSeqMod = 1u << 16;  // RTP_SEQ_MOD (A.1)
constexpr int kMaxDropout = 3000;       // MAX_DROPOUT
constexpr int kMaxMisorder = 100;       // MAX_MISORDER
constexpr int kMinSequential = 2;       // MIN_SEQUENTIAL
constexpr uint8_t kSdesCname = 1;

// The common header (RFC 3550 6.4.1): V=2, P=0, count/FMT, type, length in
// 32-bit words minus one. The length is patched by finish().
std::size_t begin(std::vector<uint8_t>& out, uint8_t count, uint8_t type) {
  const std::size_t at = out.size();
  out.push_back(static_cast<uint8_t>(0x80 | (count & 0x1F)));
  out.push_back(type);
  put16(out, 0);
  return at;
}
void finish(std::vector<uint8_t>& out, std::size_t at) {
  while ((out.size() - at) % 4) out.push_back(0);
  const auto words = static_cast<uint16_t>((out.size() - at) / 4 - 1);
  out[at + 2] = static_cast<uint8_t>(words >> 8);
  out[at + 3] = static_cast<uint8_t>(words);
}

void putBlock(std::vector<uint8_t>& out, const ReportBlock& b) {
  put32(out, b.ssrc);
  const int32_t lost = std::clamp(b.cumulative_lost, -0x800000, 0x7FFFFF);
  put32(out, static_cast<uint32_t>(b.fraction_lost) << 24 | (static_cast<uint32_t>(lost) & 0xFFFFFF));
  put32(out, b.highest_seq);
  put32(out, b.jitter);
  put32(out, b.lsr);
  put32(out, b.dlsr);
}
ReportBlock getBlock(const uint8_t* p) {
  ReportBlock b;
  b.ssrc = get32(p);
  b.fraction_lost = p[4];
  uint32_t lost = static_cast<uint32_t>(p[5]) << 16 | static_cast<uint32_t>(p[6]) << 8 | p[7];
  if (lost & 0x800000) lost |= 0xFF000000u;  // sign-extend the 24 bits
  b.cumulative_lost = static_cast<int32_t>(lost);
  b.highest_seq = get32(p + 8);
  b.jitter = get32(p + 12);
  b.lsr = get32(p + 16);
  b.dlsr = get32(p + 20);
  return b;
}

// Reads `count` report blocks from body[at...]; false when they do not fit.
bool getBlocks(std::span<const uint8_t> body, std::size_t at, int count, std::vector<ReportBlock>& out) {
  if (body.size() < at + 24 * static_cast<std::size_t>(count)) return false;
  for (int k = 0; k < count; ++k) out.push_back(getBlock(body.data() + at + 24 * static_cast<std::size_t>(k)));
  return true;
}

}  // namespace

const char* toString(RtcpError e) {
  switch (e) {
    case RtcpError::kNone: return "ok";
    case RtcpError::kTooShort: return "shorter than its RTCP packet type needs";
    case RtcpError::kBadVersion: return "RTCP version is not 2";
    case RtcpError::kBadLength: return "RTCP length field runs past the datagram";
    case RtcpError::kBadPadding: return "RTCP padding on a packet that is not the last, or longer than the packet";
    case RtcpError::kBadCount: return "RTCP report count or SDES chunk does not fit the packet";
    case RtcpError::kBadFeedback: return "RTCP feedback packet without a whole FCI";
  }
  return "?";
}

bool looksLikeRtcp(std::span<const uint8_t> d) {
  return d.size() >= 4 && (d[0] >> 6) == 2 && d[1] >= 192 && d[1] <= 223;
}

RtcpError parseCompound(std::span<const uint8_t> d, Compound& out) {
  if (d.size() < 4) return RtcpError::kTooShort;
  std::size_t at = 0;
  while (at < d.size()) {
    if (d.size() - at < 4) return RtcpError::kTooShort;
    const uint8_t* h = d.data() + at;
    if ((h[0] >> 6) != 2) return RtcpError::kBadVersion;
    const bool padded = (h[0] & 0x20) != 0;
    const int count = h[0] & 0x1F;
    const uint8_t type = h[1];
    const std::size_t len = (static_cast<std::size_t>(get16(h + 2)) + 1) * 4;
    if (len > d.size() - at) return RtcpError::kBadLength;
    std::span<const uint8_t> body = d.subspan(at + 4, len - 4);
    if (padded) {
      if (at + len != d.size()) return RtcpError::kBadPadding;
      const std::size_t pad = body.empty() ? 0 : body.back();
      if (pad == 0 || pad > body.size()) return RtcpError::kBadPadding;
      body = body.first(body.size() - pad);
    }
    switch (type) {
      case kSenderReport: {
        if (body.size() < 24) return RtcpError::kTooShort;
        SenderReport sr;
        sr.ssrc = get32(body.data());
        sr.info.ntp = static_cast<uint64_t>(get32(body.data() + 4)) << 32 | get32(body.data() + 8);
        sr.info.rtp_timestamp = get32(body.data() + 12);
        sr.info.packets = get32(body.data() + 16);
        sr.info.octets = get32(body.data() + 20);
        if (!getBlocks(body, 24, count, sr.blocks)) return RtcpError::kBadCount;
        out.sender_reports.push_back(std::move(sr));
        break;
      }
      case kReceiverReport: {
        if (body.size() < 4) return RtcpError::kTooShort;
        ReceiverReport rr;
        rr.ssrc = get32(body.data());
        if (!getBlocks(body, 4, count, rr.blocks)) return RtcpError::kBadCount;
        out.receiver_reports.push_back(std::move(rr));
        break;
      }
      case kSourceDescription: {
        // Chunks: SSRC, items (type, length, text) up to a null item, padded to 4.
        std::size_t p = 0;
        for (int c = 0; c < count; ++c) {
          if (body.size() < p + 4) return RtcpError::kBadCount;
          const uint32_t ssrc = get32(body.data() + p);
          p += 4;
          for (;;) {
            if (p >= body.size()) return RtcpError::kBadCount;
            const uint8_t item = body[p];
            if (item == 0) break;
            if (body.size() < p + 2 || body.size() < p + 2 + body[p + 1]) return RtcpError::kBadCount;
            if (item == kSdesCname)
              out.cnames.emplace_back(ssrc, std::string(reinterpret_cast<const char*>(body.data() + p + 2), body[p + 1]));
            p += 2 + body[p + 1];
          }
          p = (p + 4) & ~std::size_t{3};  // past the null item(s), to the next 32-bit boundary
        }
        break;
      }
      case kBye: {
        if (body.size() < 4 * static_cast<std::size_t>(count)) return RtcpError::kBadCount;
        for (int k = 0; k < count; ++k) out.byes.push_back(get32(body.data() + 4 * k));
        break;
      }
      case kTransportFeedback:
      case kPayloadFeedback: {
        if (body.size() < 8) return RtcpError::kTooShort;
        const uint32_t sender = get32(body.data()), media = get32(body.data() + 4);
        const auto fci = body.subspan(8);
        if (type == kTransportFeedback && count == kFmtGenericNack) {
          if (fci.empty() || fci.size() % 4) return RtcpError::kBadFeedback;
          Nack n{sender, media, {}};
          for (std::size_t k = 0; k < fci.size(); k += 4) {
            const uint16_t pid = get16(fci.data() + k), blp = get16(fci.data() + k + 2);
            n.seqs.push_back(pid);
            for (int b = 0; b < 16; ++b)
              if (blp >> b & 1) n.seqs.push_back(static_cast<uint16_t>(pid + b + 1));
          }
          out.nacks.push_back(std::move(n));
        } else if (type == kPayloadFeedback && count == kFmtPli) {
          out.plis.push_back({sender, media});  // PLI has no FCI (RFC 4585 6.3.1)
        } else {
          ++out.unknown;
        }
        break;
      }
      default: ++out.unknown;
    }
    at += len;
  }
  return RtcpError::kNone;
}

void appendSenderReport(std::vector<uint8_t>& out, uint32_t ssrc, const SenderInfo& info,
                        std::span<const ReportBlock> blocks) {
  const std::size_t n = std::min<std::size_t>(blocks.size(), 31);
  const std::size_t at = begin(out, static_cast<uint8_t>(n), kSenderReport);
  put32(out, ssrc);
  put32(out, static_cast<uint32_t>(info.ntp >> 32));
  put32(out, static_cast<uint32_t>(info.ntp));
  put32(out, info.rtp_timestamp);
  put32(out, info.packets);
  put32(out, info.octets);
  for (std::size_t k = 0; k < n; ++k) putBlock(out, blocks[k]);
  finish(out, at);
}

void appendReceiverReport(std::vector<uint8_t>& out, uint32_t ssrc, std::span<const ReportBlock> blocks) {
  const std::size_t n = std::min<std::size_t>(blocks.size(), 31);
  const std::size_t at = begin(out, static_cast<uint8_t>(n), kReceiverReport);
  put32(out, ssrc);
  for (std::size_t k = 0; k < n; ++k) putBlock(out, blocks[k]);
  finish(out, at);
}

void appendCname(std::vector<uint8_t>& out, uint32_t ssrc, const std::string& cname) {
  const std::size_t at = begin(out, 1, kSourceDescription);
  put32(out, ssrc);
  const std::size_t len = std::min<std::size_t>(cname.size(), 255);
  out.push_back(kSdesCname);
  out.push_back(static_cast<uint8_t>(len));
  out.insert(out.end(), cname.begin(), cname.begin() + static_cast<std::ptrdiff_t>(len));
  out.push_back(0);  // the null item ends the chunk; finish() pads to 32 bits
  finish(out, at);
}

void appendBye(std::vector<uint8_t>& out, uint32_t ssrc) {
  const std::size_t at = begin(out, 1, kBye);
  put32(out, ssrc);
  finish(out, at);
}

void appendNack(std::vector<uint8_t>& out, uint32_t sender_ssrc, uint32_t media_ssrc, std::span<const uint16_t> seqs) {
  if (seqs.empty()) return;
  // Sort in sequence order around the first one (wrap-around: distances mod 2^16).
  std::vector<uint16_t> s(seqs.begin(), seqs.end());
  const uint16_t base = s.front();
  std::sort(s.begin(), s.end(), [base](uint16_t a, uint16_t b) {
    return static_cast<uint16_t>(a - base) < static_cast<uint16_t>(b - base);
  });
  s.erase(std::unique(s.begin(), s.end()), s.end());
  const std::size_t at = begin(out, kFmtGenericNack, kTransportFeedback);
  put32(out, sender_ssrc);
  put32(out, media_ssrc);
  for (std::size_t k = 0; k < s.size();) {
    const uint16_t pid = s[k];
    uint16_t blp = 0;
    std::size_t j = k + 1;
    for (; j < s.size(); ++j) {
      const auto d = static_cast<uint16_t>(s[j] - pid);
      if (d < 1 || d > 16) break;
      blp = static_cast<uint16_t>(blp | 1u << (d - 1));
    }
    put16(out, pid);
    put16(out, blp);
    k = j;
  }
  finish(out, at);
}

void appendPli(std::vector<uint8_t>& out, uint32_t sender_ssrc, uint32_t media_ssrc) {
  const std::size_t at = begin(out, kFmtPli, kPayloadFeedback);
  put32(out, sender_ssrc);
  put32(out, media_ssrc);
  finish(out, at);
}

uint64_t ntpFromUnixMicros(uint64_t unix_us) {
  constexpr uint64_t kUnixToNtp_s = 2208988800ULL;  // 1900-01-01 to 1970-01-01
  const uint64_t s = unix_us / 1000000 + kUnixToNtp_s;
  const uint64_t frac = ((unix_us % 1000000) << 32) / 1000000;
  return s << 32 | frac;
}

std::optional<double> roundTripSeconds(uint32_t arrival_middle, uint32_t lsr, uint32_t dlsr) {
  if (lsr == 0) return std::nullopt;
  // Modulo 2^32 arithmetic of the 16.16 fixed-point times (RFC 3550 6.4.1).
  const auto rtt = static_cast<int32_t>(arrival_middle - lsr - dlsr);
  if (rtt < 0) return std::nullopt;
  return rtt / 65536.0;
}

void ReceiverStats::init(uint16_t seq) {
  base_seq_ = seq;
  max_seq_ = seq;
  bad_seq_ = kSeqMod + 1;
  cycles_ = 0;
  received_ = 0;
  received_prior_ = 0;
  expected_prior_ = 0;
}

bool ReceiverStats::onPacket(uint16_t seq, uint32_t rtp_timestamp, uint64_t arrival_us) {
  // A.1 update_seq (init_seq on the first packet, then MIN_SEQUENTIAL in a row).
  if (!seen_) {
    seen_ = true;
    init(seq);
    max_seq_ = static_cast<uint16_t>(seq - 1);
    probation_ = kMinSequential;
  }
  const auto udelta = static_cast<uint16_t>(seq - max_seq_);
  if (probation_ > 0) {
    if (seq == static_cast<uint16_t>(max_seq_ + 1)) {
      --probation_;
      max_seq_ = seq;
      if (probation_ == 0) init(seq);
    } else {
      probation_ = kMinSequential - 1;
      max_seq_ = seq;
    }
    if (probation_ > 0) return false;
  } else if (udelta < kMaxDropout) {
    if (seq < max_seq_) cycles_ += kSeqMod;  // wrapped
    max_seq_ = seq;
  } else if (udelta <= kSeqMod - kMaxMisorder) {
    // A very large jump: the source restarted if the next packet follows it.
    if (seq == bad_seq_) {
      init(seq);
    } else {
      bad_seq_ = (seq + 1u) & (kSeqMod - 1);
      return false;
    }
  }
  // else: a duplicate or reordered packet; counted as received (A.1).
  ++received_;
  // A.8 jitter, in timestamp units: transit = arrival (RTP units) - timestamp.
  const auto arrival = static_cast<int64_t>(arrival_us * clock_rate_ / 1000000);
  const int64_t transit = arrival - static_cast<int64_t>(rtp_timestamp);
  if (have_transit_) {
    int64_t d = transit - transit_;
    // RTP timestamps wrap at 2^32: take the difference modulo 2^32, signed.
    d = static_cast<int32_t>(static_cast<uint32_t>(d));
    if (d < 0) d = -d;
    jitter_ += static_cast<uint32_t>(d) - ((jitter_ + 8) >> 4);
  }
  transit_ = transit;
  have_transit_ = true;
  return true;
}

void ReceiverStats::onSenderReport(uint64_t ntp, uint64_t arrival_us) {
  lsr_ = ntpMiddle(ntp);
  lsr_arrival_us_ = arrival_us;
}

int64_t ReceiverStats::cumulativeLost() const {
  if (received_ == 0) return 0;
  const int64_t expected = static_cast<int64_t>(extendedHighest()) - base_seq_ + 1;
  return expected - static_cast<int64_t>(received_);
}

ReportBlock ReceiverStats::report(uint32_t source_ssrc, uint64_t now_us) {
  ReportBlock b;
  b.ssrc = source_ssrc;
  if (received_ > 0) {
    // A.3: fraction lost over the interval since the last report.
    const auto expected = static_cast<uint32_t>(extendedHighest() - base_seq_ + 1);
    const uint32_t expected_interval = expected - expected_prior_;
    const auto received_interval = static_cast<int64_t>(received_ - received_prior_);
    expected_prior_ = expected;
    received_prior_ = received_;
    const int64_t lost_interval = static_cast<int64_t>(expected_interval) - received_interval;
    b.fraction_lost = expected_interval == 0 || lost_interval <= 0
                          ? 0
                          : static_cast<uint8_t>(std::min<int64_t>(255, (lost_interval << 8) / expected_interval));
    b.cumulative_lost = static_cast<int32_t>(std::clamp<int64_t>(cumulativeLost(), -0x800000, 0x7FFFFF));
    b.highest_seq = extendedHighest();
  }
  b.jitter = jitter_ >> 4;
  b.lsr = lsr_;
  if (lsr_ != 0 && now_us >= lsr_arrival_us_) b.dlsr = static_cast<uint32_t>((now_us - lsr_arrival_us_) * 65536 / 1000000);
  return b;
}

}  // namespace inspect::video::rtcp
