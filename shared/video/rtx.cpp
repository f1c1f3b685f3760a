#include "shared/video/rtx.hpp"

#include <algorithm>
#include <cmath>

#include "shared/video/byte_order.hpp"

namespace inspect::video {
namespace {

// Length of the RTP header proper (fixed part, CSRCs, extension) of a
// datagram parseRtp accepted: where its payload starts.
std::size_t headerLength(std::span<const uint8_t> d) {
  std::size_t off = kRtpHeaderSize + 4u * (d[0] & 0x0F);
  if (d[0] & 0x10) off += 4 + 4u * get16(d.data() + off + 2);
  return off;
}

void setHeader(std::vector<uint8_t>& v, uint8_t payload_type, uint16_t seq, uint32_t ssrc) {
  v[0] = static_cast<uint8_t>(v[0] & ~0x20);  // no padding
  v[1] = static_cast<uint8_t>((v[1] & 0x80) | (payload_type & 0x7F));
  v[2] = static_cast<uint8_t>(seq >> 8);
  v[3] = static_cast<uint8_t>(seq);
  v[8] = static_cast<uint8_t>(ssrc >> 24);
  v[9] = static_cast<uint8_t>(ssrc >> 16);
  v[10] = static_cast<uint8_t>(ssrc >> 8);
  v[11] = static_cast<uint8_t>(ssrc);
}

}  // namespace

std::optional<std::vector<uint8_t>> makeRtx(std::span<const uint8_t> original, uint32_t rtx_ssrc,
                                            uint8_t rtx_payload_type, uint16_t rtx_seq) {
  RtpPacket p;
  if (parseRtp(original, p) != RtpError::kNone) return std::nullopt;
  const std::size_t header = headerLength(original);
  std::vector<uint8_t> v;
  v.reserve(header + 2 + p.payload.size());
  v.insert(v.end(), original.begin(), original.begin() + static_cast<std::ptrdiff_t>(header));
  setHeader(v, rtx_payload_type, rtx_seq, rtx_ssrc);
  put16(v, p.seq);  // OSN (RFC 4588 4)
  v.insert(v.end(), p.payload.begin(), p.payload.end());
  return v;
}

const char* toString(RtxError e) {
  switch (e) {
    case RtxError::kNone: return "ok";
    case RtxError::kNotRtp: return "RTX datagram is not an RTP packet";
    case RtxError::kWrongPayloadType: return "RTX datagram has another payload type";
    case RtxError::kNoOriginalSeq: return "RTX payload shorter than its original sequence number";
  }
  return "?";
}

RtxError unwrapRtx(std::span<const uint8_t> rtx, uint8_t rtx_payload_type, uint8_t media_payload_type,
                   uint32_t media_ssrc, std::vector<uint8_t>& original) {
  RtpPacket p;
  if (parseRtp(rtx, p) != RtpError::kNone) return RtxError::kNotRtp;
  if (p.payload_type != rtx_payload_type) return RtxError::kWrongPayloadType;
  if (p.payload.size() < 2) return RtxError::kNoOriginalSeq;
  const std::size_t header = headerLength(rtx);
  original.assign(rtx.begin(), rtx.begin() + static_cast<std::ptrdiff_t>(header));
  setHeader(original, media_payload_type, get16(p.payload.data()), media_ssrc);
  original.insert(original.end(), p.payload.begin() + 2, p.payload.end());
  return RtxError::kNone;
}

void RetransmissionHistory::expire(uint64_t now_us) {
  while (!packets_.empty() &&
         (packets_.size() > capacity_ || now_us > packets_.front().sent_us + max_age_us_)) {
    bytes_ -= packets_.front().datagram.size();
    packets_.pop_front();
  }
}

void RetransmissionHistory::remember(uint16_t seq, std::span<const uint8_t> datagram, uint64_t sent_us) {
  if (capacity_ == 0) return;
  packets_.push_back({seq, sent_us, std::vector<uint8_t>(datagram.begin(), datagram.end())});
  bytes_ += datagram.size();
  expire(sent_us);
}

RetransmissionHistory::Sent* RetransmissionHistory::locate(uint16_t seq, uint64_t now_us) {
  // Sequence numbers are consecutive in sending order: index by distance
  // from the newest, then check (a wrap or a gap falls back to a scan).
  if (packets_.empty()) return nullptr;
  const auto back = static_cast<uint16_t>(packets_.back().seq - seq);
  Sent* hit = nullptr;
  if (back < packets_.size() && packets_[packets_.size() - 1 - back].seq == seq) {
    hit = &packets_[packets_.size() - 1 - back];
  } else {
    for (auto& s : packets_)
      if (s.seq == seq) hit = &s;
  }
  if (!hit || now_us > hit->sent_us + max_age_us_) return nullptr;
  return hit;
}

const std::vector<uint8_t>* RetransmissionHistory::find(uint16_t seq, uint64_t now_us) const {
  const Sent* hit = const_cast<RetransmissionHistory*>(this)->locate(seq, now_us);
  return hit ? &hit->datagram : nullptr;
}

RetransmissionHistory::Plan RetransmissionHistory::planRetransmission(uint16_t seq, uint64_t now_us,
                                                                      uint64_t repeat_us) {
  Sent* hit = locate(seq, now_us);
  if (!hit) return {};
  if (hit->rtx_count > 0 && now_us < hit->rtx_us + repeat_us) return {&hit->datagram, 0};
  const int copies = hit->rtx_count > 0 ? 2 : 1;
  ++hit->rtx_count;
  hit->rtx_us = now_us;
  return {&hit->datagram, copies};
}

void NackList::onPacket(uint16_t seq, uint64_t now_us) {
  if (!started_) {
    started_ = true;
    highest_ = seq;
    return;
  }
  const auto ahead = static_cast<uint16_t>(seq - highest_);
  if (ahead != 0 && ahead < 0x8000) {
    // Newer: everything between was skipped. A jump larger than the list's
    // bound keeps only the newest of the gap.
    const uint16_t gap = static_cast<uint16_t>(ahead - 1);
    const auto kept = static_cast<uint16_t>(std::min<std::size_t>(gap, s_.max_missing));
    given_up_ += gap - kept;
    const auto from = static_cast<uint16_t>(seq - kept);
    for (uint16_t q = from; q != seq; ++q) missing_.push_back({q, now_us});
    while (missing_.size() > s_.max_missing) {
      missing_.pop_front();
      ++given_up_;
    }
    highest_ = seq;
    return;
  }
  // Older (or the highest: a duplicate, or a tail probe's packet): a
  // reordered or retransmitted packet fills its hole.
  const auto it = std::find_if(missing_.begin(), missing_.end(), [seq](const Missing& m) { return m.seq == seq; });
  if (it != missing_.end()) {
    if (it->tries > 0) ++recovered_;
    missing_.erase(it);
  }
}

std::size_t NackList::expireBefore(uint16_t next) {
  const std::size_t n =
      std::erase_if(missing_, [next](const Missing& m) { return static_cast<uint16_t>(m.seq - next) >= 0x8000; });
  given_up_ += n;
  return n;
}

bool NackList::probeTail(uint64_t now_us) {
  if (!started_) return false;
  highest_ = static_cast<uint16_t>(highest_ + 1);
  missing_.push_back({highest_, now_us});
  ++probes_;
  while (missing_.size() > s_.max_missing) {
    missing_.pop_front();
    ++given_up_;
  }
  return true;
}

uint64_t NackList::retryInterval(uint64_t rtt_us) const {
  return std::max<uint64_t>(s_.min_retry_us, static_cast<uint64_t>(std::llround(s_.retry_rtts * static_cast<double>(rtt_us))));
}

std::vector<uint16_t> NackList::due(uint64_t now_us, uint64_t rtt_us) {
  std::vector<uint16_t> out;
  const uint64_t retry = retryInterval(rtt_us);
  for (auto& m : missing_) {
    if (m.tries >= s_.max_tries) continue;
    const bool first = m.tries == 0 && now_us >= m.first_us + s_.reorder_wait_us;
    const bool again = m.tries > 0 && now_us >= m.last_nack_us + retry;
    if (!first && !again) continue;
    ++m.tries;
    m.last_nack_us = now_us;
    out.push_back(m.seq);
    ++nacked_;
  }
  return out;
}

std::vector<uint16_t> NackList::expire(uint64_t deadline_us, uint64_t now_us, uint64_t rtt_us) {
  std::vector<uint16_t> out;
  const uint64_t retry = retryInterval(rtt_us);
  std::erase_if(missing_, [&](const Missing& m) {
    const bool late = m.first_us < deadline_us;
    const bool exhausted = m.tries >= s_.max_tries && now_us >= m.last_nack_us + retry;
    if (late || exhausted) out.push_back(m.seq);
    return late || exhausted;
  });
  given_up_ += out.size();
  return out;
}

std::optional<uint64_t> NackList::firstMissedUs(uint16_t seq) const {
  const auto it = std::find_if(missing_.begin(), missing_.end(), [seq](const Missing& m) { return m.seq == seq; });
  if (it == missing_.end()) return std::nullopt;
  return it->first_us;
}

bool NackList::missing(uint16_t seq) const { return firstMissedUs(seq).has_value(); }

}  // namespace inspect::video
