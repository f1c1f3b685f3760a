#pragma once
// Retransmission for the video path (issue 22): RFC 4588 RTX packets (own
// payload type and SSRC, the original sequence number first in the
// payload), the sender's bounded history of what it sent, and the
// receiver's list of missing packets with when to NACK them (RFC 4585) and
// when to give up. Pure byte work and arithmetic; times are arguments.
// docs/video.md ("Retransmission").
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <span>
#include <vector>

#include "shared/video/rtp_h264.hpp"

namespace inspect::video {

inline constexpr uint8_t kRtxPayloadType = 97;  // a=rtpmap:97 rtx/90000, a=fmtp:97 apt=96

/// An RTX packet for an original RTP datagram (RFC 4588 4): the original's
/// header (its CSRCs and header extension too, so a frame's first packet
/// keeps its capture time) with the RTX payload type, SSRC and sequence
/// number; the payload is the original sequence number (2 bytes) followed by
/// the original payload. Padding is not carried. nullopt when `original` is
/// not an RTP packet we accept.
std::optional<std::vector<uint8_t>> makeRtx(std::span<const uint8_t> original, uint32_t rtx_ssrc,
                                            uint8_t rtx_payload_type, uint16_t rtx_seq);

/// Why an RTX datagram was not turned back into its original.
enum class RtxError { kNone, kNotRtp, kWrongPayloadType, kNoOriginalSeq };
const char* toString(RtxError e);

/// The original datagram an RTX packet carries, with `media_payload_type`
/// and `media_ssrc` put back.
RtxError unwrapRtx(std::span<const uint8_t> rtx, uint8_t rtx_payload_type, uint8_t media_payload_type,
                   uint32_t media_ssrc, std::vector<uint8_t>& original);

/// The sender's copy of the packets it sent lately, by sequence number: at
/// most `capacity` packets and none older than `max_age_us`.
class RetransmissionHistory {
 public:
  RetransmissionHistory(std::size_t capacity, uint64_t max_age_us) : capacity_(capacity), max_age_us_(max_age_us) {}

  void remember(uint16_t seq, std::span<const uint8_t> datagram, uint64_t sent_us);
  /// The datagram sent as `seq`, if still held at `now_us`.
  const std::vector<uint8_t>* find(uint16_t seq, uint64_t now_us) const;
  /// What to send for a NACK of `seq` at `now_us`: the datagram (null when no
  /// longer held) and how many RTX copies. None for a repeat within
  /// `repeat_us` of its last retransmission (the receiver sends each NACK
  /// twice: the second copy is for when the first is lost); two when it was
  /// retransmitted before (a retry: that retransmission was lost); else one.
  struct Plan {
    const std::vector<uint8_t>* datagram = nullptr;
    int copies = 0;
  };
  Plan planRetransmission(uint16_t seq, uint64_t now_us, uint64_t repeat_us);
  std::size_t size() const { return packets_.size(); }
  std::size_t bytes() const { return bytes_; }

 private:
  struct Sent {
    uint16_t seq;
    uint64_t sent_us;
    std::vector<uint8_t> datagram;
    uint64_t rtx_us = 0;  // last retransmission
    uint32_t rtx_count = 0;
  };
  Sent* locate(uint16_t seq, uint64_t now_us);
  void expire(uint64_t now_us);
  std::size_t capacity_;
  uint64_t max_age_us_;
  std::deque<Sent> packets_;  // in the order sent
  std::size_t bytes_ = 0;
};

/// Settings of the receiver's NACK list.
struct NackSettings {
  uint64_t reorder_wait_us = 5000;   // a gap this young may still be reordering: wait before the first NACK
  double retry_rtts = 1.25;          // NACK again after this many RTTs without the packet
  uint64_t min_retry_us = 10000;     // ...but not sooner than this
  int max_tries = 4;                 // NACKs per packet before giving up
  std::size_t max_missing = 512;     // the list's bound (the oldest go first)
};

/// The receiver's missing packets (one source). Feed every arriving
/// sequence number (originals and recovered retransmissions alike); ask
/// `due` which to NACK now; `expired` says which were given up.
class NackList {
 public:
  explicit NackList(NackSettings s = {}) : s_(s) {}

  /// A packet arrived (original or recovered). Sequence numbers skipped
  /// since the highest one seen become missing.
  void onPacket(uint16_t seq, uint64_t now_us);
  /// The sequence numbers to NACK now, given the current round-trip time;
  /// each is counted as one more try.
  std::vector<uint16_t> due(uint64_t now_us, uint64_t rtt_us);
  /// Gives up on packets whose frame can no longer be shown in time: those
  /// first missed before `deadline_us`, and those past max_tries whose last
  /// NACK had a retry interval to come back. Returns them.
  std::vector<uint16_t> expire(uint64_t deadline_us, uint64_t now_us, uint64_t rtt_us);
  /// Gives up on the packets before `next` (in 16-bit order): those the
  /// reorder buffer has released without. Returns how many.
  std::size_t expireBefore(uint16_t next);
  /// The newest packet had no marker and nothing came after it for a while:
  /// the rest of its frame may be lost, and no later packet shows that until
  /// the next frame. Counts the next sequence number as missing (NACKed like
  /// the others; a sender that has not sent it yet has nothing to resend).
  bool probeTail(uint64_t now_us);
  uint64_t tailProbes() const { return probes_; }
  /// The highest sequence number seen (or probed).
  uint16_t highest() const { return highest_; }
  bool missing(uint16_t seq) const;
  /// When `seq` was first found missing; none when it is not missing.
  std::optional<uint64_t> firstMissedUs(uint16_t seq) const;
  std::size_t size() const { return missing_.size(); }
  const NackSettings& settings() const { return s_; }
  uint64_t nacked() const { return nacked_; }
  uint64_t recovered() const { return recovered_; }
  uint64_t givenUp() const { return given_up_; }

 private:
  struct Missing {
    uint16_t seq;
    uint64_t first_us;
    uint64_t last_nack_us = 0;
    int tries = 0;
  };
  uint64_t retryInterval(uint64_t rtt_us) const;
  NackSettings s_;
  uint64_t probes_ = 0;
  bool started_ = false;
  uint16_t highest_ = 0;
  std::deque<Missing> missing_;  // in sequence order
  uint64_t nacked_ = 0, recovered_ = 0, given_up_ = 0;
};

}  // namespace inspect::video
