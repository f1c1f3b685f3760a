#include "shared/video/rtp_h264.hpp"

#include <algorithm>

#include "shared/video/byte_order.hpp"

namespace inspect::video {
namespace {

constexpr uint16_t kExtProfile = 0xBEDE;   // RFC 8285 one-byte header
constexpr std::size_t kExtBytes = 4 + 12;  // profile + length, then 1 + 8 bytes padded to 12
constexpr uint8_t kStartCode[4] = {0, 0, 0, 1};

// H.264 7.4.1: no byte-aligned 0x000000, 0x000001 or 0x000002 inside a NAL
// unit (the encoder's emulation prevention keeps start codes out) and no
// 0x00 as its last byte. A unit that breaks this would be cut into other
// units by an Annex B reader (the decoder) than the ones it came in: the
// frame's keyframe and parameter-set flags would be wrong.
bool wellFormedNal(std::span<const uint8_t> nal) {
  if (nal.empty() || nal.back() == 0) return false;
  for (std::size_t i = 0; i + 2 < nal.size(); ++i)
    if (nal[i] == 0 && nal[i + 1] == 0 && nal[i + 2] <= 2) return false;
  return true;
}

}  // namespace

const char* toString(RtpError e) {
  switch (e) {
    case RtpError::kNone: return "ok";
    case RtpError::kTooShort: return "shorter than an RTP header";
    case RtpError::kBadVersion: return "RTP version is not 2";
    case RtpError::kBadCsrc: return "CSRC list runs past the end";
    case RtpError::kBadExtension: return "header extension runs past the end";
    case RtpError::kBadPadding: return "padding longer than the payload";
  }
  return "?";
}

std::vector<std::span<const uint8_t>> splitAnnexB(std::span<const uint8_t> b) {
  std::vector<std::span<const uint8_t>> out;
  const std::size_t n = b.size();
  std::size_t i = 0, start = n;  // start of the current NAL (n = none yet)
  auto close = [&](std::size_t end) {
    if (start >= end) return;
    while (end > start && b[end - 1] == 0) --end;  // trailing zero bytes belong to the next start code
    if (end > start) out.push_back(b.subspan(start, end - start));
  };
  while (i + 2 < n) {
    if (b[i] == 0 && b[i + 1] == 0 && b[i + 2] == 1) {
      close(i);
      i += 3;
      start = i;
    } else {
      ++i;
    }
  }
  close(n);
  return out;
}

RtpError parseRtp(std::span<const uint8_t> d, RtpPacket& out) {
  if (d.size() < kRtpHeaderSize) return RtpError::kTooShort;
  const uint8_t* p = d.data();
  if ((p[0] >> 6) != 2) return RtpError::kBadVersion;
  const bool padding = p[0] & 0x20, extension = p[0] & 0x10;
  const std::size_t cc = p[0] & 0x0F;
  out = {};
  out.marker = p[1] & 0x80;
  out.payload_type = p[1] & 0x7F;
  out.seq = get16(p + 2);
  out.timestamp = get32(p + 4);
  out.ssrc = get32(p + 8);
  std::size_t off = kRtpHeaderSize + 4 * cc;
  if (off > d.size()) return RtpError::kBadCsrc;
  if (extension) {
    if (off + 4 > d.size()) return RtpError::kBadExtension;
    const uint16_t profile = get16(p + off);
    const std::size_t len = 4u * get16(p + off + 2);
    const std::size_t ext = off + 4;
    if (ext + len > d.size()) return RtpError::kBadExtension;
    if (profile == kExtProfile) {
      std::size_t k = ext;
      while (k < ext + len) {
        const uint8_t h = p[k];
        if (h == 0) {  // padding byte
          ++k;
          continue;
        }
        const uint8_t id = h >> 4;
        const std::size_t l = (h & 0x0F) + 1u;
        if (id == 15 || k + 1 + l > ext + len) break;  // reserved id / truncated: stop reading elements
        if (id == kCaptureTimeExtId && l == 8) {
          uint64_t us = 0;
          for (std::size_t j = 0; j < 8; ++j) us = us << 8 | p[k + 1 + j];
          out.capture_us = us;
        }
        k += 1 + l;
      }
    }
    off = ext + len;
  }
  std::size_t end = d.size();
  if (padding) {
    const std::size_t pad = p[d.size() - 1];
    if (pad == 0 || off + pad > end) return RtpError::kBadPadding;
    end -= pad;
  }
  out.payload = d.subspan(off, end - off);
  return RtpError::kNone;
}

// --- packetizer ---------------------------------------------------------------

H264Packetizer::H264Packetizer(uint32_t ssrc, std::size_t max_payload, uint16_t first_seq)
    : ssrc_(ssrc), max_payload_(std::max<std::size_t>(max_payload, 64)), seq_(first_seq) {}

void H264Packetizer::emit(std::vector<std::vector<uint8_t>>& out, bool marker, uint32_t ts,
                          const uint64_t* capture_us, std::span<const uint8_t> a, std::span<const uint8_t> b) {
  std::vector<uint8_t> pk;
  pk.reserve(kRtpHeaderSize + kExtBytes + a.size() + b.size());
  pk.push_back(static_cast<uint8_t>(0x80 | (capture_us ? 0x10 : 0)));
  pk.push_back(static_cast<uint8_t>((marker ? 0x80 : 0) | kPayloadType));
  put16(pk, seq_++);
  put32(pk, ts);
  put32(pk, ssrc_);
  if (capture_us) {
    put16(pk, kExtProfile);
    put16(pk, 3);  // 12 bytes of elements
    pk.push_back(static_cast<uint8_t>(kCaptureTimeExtId << 4 | (8 - 1)));
    for (int s = 56; s >= 0; s -= 8) pk.push_back(static_cast<uint8_t>(*capture_us >> s));
    pk.insert(pk.end(), 3, 0);  // padding to a 32-bit boundary
  }
  pk.insert(pk.end(), a.begin(), a.end());
  pk.insert(pk.end(), b.begin(), b.end());
  out.push_back(std::move(pk));
}

std::size_t H264Packetizer::packetize(std::span<const uint8_t> annexb, uint32_t ts, uint64_t capture_us,
                                      std::vector<std::vector<uint8_t>>& out) {
  const auto nals = splitAnnexB(annexb);
  const std::size_t before = out.size();
  bool first = true;
  for (std::size_t i = 0; i < nals.size(); ++i) {
    const auto nal = nals[i];
    const bool last_nal = i + 1 == nals.size();
    // The first packet of a frame also carries the capture-time extension.
    const std::size_t budget = max_payload_ - (first ? kExtBytes : 0);
    if (nal.size() <= budget) {  // single NAL unit packet (RFC 6184 5.6)
      emit(out, last_nal, ts, first ? &capture_us : nullptr, nal);
      first = false;
      continue;
    }
    // FU-A (RFC 6184 5.8): indicator = F|NRI|28, header = S|E|R|type, then the NAL's bytes after its header.
    const uint8_t indicator = static_cast<uint8_t>((nal[0] & 0xE0) | kNalFuA);
    const uint8_t type = nalType(nal[0]);
    std::size_t pos = 1;
    while (pos < nal.size()) {
      const std::size_t room = max_payload_ - (first ? kExtBytes : 0) - 2;
      const std::size_t take = std::min(room, nal.size() - pos);
      const bool start = pos == 1, end = pos + take == nal.size();
      const uint8_t hdr[2] = {indicator, static_cast<uint8_t>((start ? 0x80 : 0) | (end ? 0x40 : 0) | type)};
      emit(out, end && last_nal, ts, first ? &capture_us : nullptr, hdr, nal.subspan(pos, take));
      first = false;
      pos += take;
    }
  }
  return out.size() - before;
}

// --- reorder buffer -----------------------------------------------------------

bool ReorderBuffer::push(uint16_t seq, std::vector<uint8_t> datagram) {
  if (!started_) {
    started_ = true;
    next_ = seq;
  }
  const uint16_t d = static_cast<uint16_t>(seq - next_);
  if (d >= 0x8000) {  // before what was released already
    ++late_;
    return false;
  }
  auto it = std::lower_bound(held_.begin(), held_.end(), d, [&](const auto& e, uint16_t key) {
    return static_cast<uint16_t>(e.first - next_) < key;
  });
  if (it != held_.end() && it->first == seq) {
    ++duplicates_;
    return false;
  }
  held_.insert(it, {seq, std::move(datagram)});
  return true;
}

void ReorderBuffer::releaseFront(std::vector<std::pair<uint32_t, std::vector<uint8_t>>>& out) {
  const uint16_t d = static_cast<uint16_t>(held_.front().first - next_);
  out.emplace_back(d, std::move(held_.front().second));
  next_ = static_cast<uint16_t>(held_.front().first + 1);
  held_.erase(held_.begin());
}

void ReorderBuffer::pop(std::vector<std::pair<uint32_t, std::vector<uint8_t>>>& out) {
  // Wait for a missing one a little longer, unless more than `window` are held.
  while (!held_.empty() && (held_.front().first == next_ || held_.size() > window_)) releaseFront(out);
}

void ReorderBuffer::flush(std::vector<std::pair<uint32_t, std::vector<uint8_t>>>& out) {
  while (!held_.empty()) releaseFront(out);
}

void ReorderBuffer::skipGap(std::vector<std::pair<uint32_t, std::vector<uint8_t>>>& out) {
  if (held_.empty()) return;
  releaseFront(out);
  pop(out);
}

// --- depacketizer -------------------------------------------------------------

void H264Depacketizer::noteType(uint8_t type) {
  cur_.keyframe = cur_.keyframe || type == kNalIdr;
  cur_sps_ = cur_sps_ || type == kNalSps;
  cur_pps_ = cur_pps_ || type == kNalPps;
}

void H264Depacketizer::appendNal(std::span<const uint8_t> nal) {
  if (nal.empty()) return;
  if (!wellFormedNal(nal)) {
    ++c_.bad_payload;
    cur_broken_ = true;
    return;
  }
  noteType(nalType(nal[0]));
  cur_.annexb.insert(cur_.annexb.end(), kStartCode, kStartCode + 4);
  cur_.annexb.insert(cur_.annexb.end(), nal.begin(), nal.end());
}

std::optional<Frame> H264Depacketizer::finish() {
  if (!have_cur_) return std::nullopt;
  have_cur_ = false;
  const bool broken = cur_broken_ || in_fu_ || cur_.annexb.empty();
  cur_broken_ = in_fu_ = false;
  Frame f = std::move(cur_);
  cur_ = {};
  f.has_parameter_sets = cur_sps_ && cur_pps_;
  cur_sps_ = cur_pps_ = false;
  if (broken) {
    ++c_.frames_dropped;
    need_keyframe_ = true;
    return std::nullopt;
  }
  if (f.keyframe) need_keyframe_ = false;
  ++c_.frames;
  return f;
}

std::optional<Frame> H264Depacketizer::push(const RtpPacket& p, uint32_t skipped) {
  ++c_.packets;
  c_.lost_packets += skipped;
  if (skipped > 0) need_keyframe_ = true;  // whatever was lost, the decoder's references are now suspect
  if (have_cur_ && p.timestamp != cur_.timestamp) {
    cur_broken_ = true;  // the previous frame never saw its marker packet: dropped
    (void)finish();
  }
  if (!have_cur_) {
    have_cur_ = true;
    cur_.timestamp = p.timestamp;
    // Packets lost just before a frame's first packet may have been its start,
    // unless this packet carries the capture-time extension: our packetizer
    // puts it on a frame's first packet only, so the loss was an earlier frame.
    cur_broken_ = skipped > 0 && !p.capture_us.has_value();
  } else if (skipped > 0) {
    cur_broken_ = true;
  }
  if (p.capture_us && !cur_.capture_us) cur_.capture_us = p.capture_us;

  const auto pl = p.payload;
  if (pl.empty()) {
    ++c_.bad_payload;
    cur_broken_ = true;
  } else {
    const uint8_t t = nalType(pl[0]);
    if (t >= 1 && t <= 23) {
      if (in_fu_) cur_broken_ = true;  // an FU-A never ended
      in_fu_ = false;
      appendNal(pl);
    } else if (t == kNalStapA) {
      std::size_t k = 1;
      bool ok = pl.size() > 3;
      while (ok && k + 2 <= pl.size()) {
        const std::size_t len = get16(pl.data() + k);
        k += 2;
        if (len == 0 || k + len > pl.size()) {
          ok = false;
          break;
        }
        appendNal(pl.subspan(k, len));
        k += len;
      }
      if (!ok || k != pl.size()) {
        ++c_.bad_payload;
        cur_broken_ = true;
      }
    } else if (t == kNalFuA && pl.size() >= 3) {
      const bool start = pl[1] & 0x80, end = pl[1] & 0x40;
      if (start) {
        if (in_fu_) cur_broken_ = true;
        in_fu_ = true;
        const uint8_t hdr = static_cast<uint8_t>((pl[0] & 0xE0) | nalType(pl[1]));
        noteType(nalType(pl[1]));
        cur_.annexb.insert(cur_.annexb.end(), kStartCode, kStartCode + 4);
        fu_start_ = cur_.annexb.size();
        cur_.annexb.push_back(hdr);
      } else if (!in_fu_) {
        cur_broken_ = true;  // its start was lost
      }
      if (in_fu_) cur_.annexb.insert(cur_.annexb.end(), pl.begin() + 2, pl.end());
      if (end && in_fu_ && !wellFormedNal(std::span(cur_.annexb).subspan(fu_start_))) {
        ++c_.bad_payload;
        cur_broken_ = true;
      }
      if (end) in_fu_ = false;
    } else {
      ++c_.bad_payload;  // STAP-B, MTAP, FU-B, reserved: not sent by mode-1 senders
      cur_broken_ = true;
    }
  }
  if (p.marker) return finish();
  return std::nullopt;
}

}  // namespace inspect::video
