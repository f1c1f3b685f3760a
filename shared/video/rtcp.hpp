#pragma once
// RTCP for the video path (issue 22): RFC 3550 sender and receiver reports,
// SDES CNAME and BYE; RFC 4585 transport-layer generic NACK and
// payload-specific PLI. Pure byte work and arithmetic: no sockets, no clocks
// of its own (times come in as arguments). docs/video.md ("RTCP") has the
// wire details.
//
// - parseCompound accepts a compound packet (RFC 3550 6.1) or a reduced-size
//   one (RFC 5506: a feedback packet alone); every packet must be version 2,
//   fit the datagram by its length field, and only the last may be padded.
//   Unknown packet types are skipped (counted), not errors.
// - ReceiverStats is RFC 3550 appendix A.1 (sequence numbers with wrap,
//   restarts and probation), A.3 (expected, lost, fraction lost per
//   interval) and A.8 (interarrival jitter) for one source.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace inspect::video::rtcp {

inline constexpr uint8_t kSenderReport = 200;
inline constexpr uint8_t kReceiverReport = 201;
inline constexpr uint8_t kSourceDescription = 202;
inline constexpr uint8_t kBye = 203;
inline constexpr uint8_t kTransportFeedback = 205;  // RTPFB (RFC 4585 6.2)
inline constexpr uint8_t kPayloadFeedback = 206;    // PSFB (RFC 4585 6.3)
inline constexpr uint8_t kFmtGenericNack = 1;       // RTPFB FMT 1
inline constexpr uint8_t kFmtPli = 1;               // PSFB FMT 1

/// One reception report block (RFC 3550 6.4.1).
struct ReportBlock {
  uint32_t ssrc = 0;              // the source this block is about
  uint8_t fraction_lost = 0;      // of the last interval, 1/256 units
  int32_t cumulative_lost = 0;    // 24-bit signed on the wire (clamped)
  uint32_t highest_seq = 0;       // extended highest sequence number received
  uint32_t jitter = 0;            // interarrival jitter, RTP timestamp units
  uint32_t lsr = 0;               // middle 32 bits of the last SR's NTP time (0: none yet)
  uint32_t dlsr = 0;              // delay since that SR, 1/65536 s
};

/// The sender information of an SR (RFC 3550 6.4.1).
struct SenderInfo {
  uint64_t ntp = 0;         // NTP timestamp (64-bit fixed point, seconds since 1900)
  uint32_t rtp_timestamp = 0;
  uint32_t packets = 0;     // sender's packet count
  uint32_t octets = 0;      // sender's payload octet count
};

struct SenderReport {
  uint32_t ssrc = 0;
  SenderInfo info;
  std::vector<ReportBlock> blocks;
};

struct ReceiverReport {
  uint32_t ssrc = 0;
  std::vector<ReportBlock> blocks;
};

/// A generic NACK (RFC 4585 6.2.1), its PID/BLP pairs expanded.
struct Nack {
  uint32_t sender_ssrc = 0;
  uint32_t media_ssrc = 0;
  std::vector<uint16_t> seqs;  // the lost packets' sequence numbers, in wire order
};

/// A picture loss indication (RFC 4585 6.3.1).
struct Pli {
  uint32_t sender_ssrc = 0;
  uint32_t media_ssrc = 0;
};

/// What one datagram carried.
struct Compound {
  std::vector<SenderReport> sender_reports;
  std::vector<ReceiverReport> receiver_reports;
  std::vector<std::pair<uint32_t, std::string>> cnames;  // (ssrc, CNAME)
  std::vector<uint32_t> byes;
  std::vector<Nack> nacks;
  std::vector<Pli> plis;
  std::size_t unknown = 0;  // packets of other types or formats, skipped
};

/// Why a datagram was not RTCP we accept.
enum class RtcpError {
  kNone,
  kTooShort,      // under 4 bytes, or a packet's body shorter than its type needs
  kBadVersion,    // not version 2
  kBadLength,     // a length field runs past the datagram
  kBadPadding,    // padding on a packet that is not the last, or longer than the packet
  kBadCount,      // a report count or SDES chunk that does not fit the packet
  kBadFeedback,   // a feedback packet without its FCI, or a NACK with a partial FCI entry
};
const char* toString(RtcpError e);

/// Parses a whole datagram; on error `out` holds what came before the bad packet.
RtcpError parseCompound(std::span<const uint8_t> datagram, Compound& out);

/// Whether the datagram looks like RTCP rather than RTP when both share a
/// port (RFC 5761 4: payload type byte 192-223).
bool looksLikeRtcp(std::span<const uint8_t> datagram);

// --- builders: each appends one RTCP packet to `out` (concatenate for a compound) ---

void appendSenderReport(std::vector<uint8_t>& out, uint32_t ssrc, const SenderInfo& info,
                        std::span<const ReportBlock> blocks = {});
void appendReceiverReport(std::vector<uint8_t>& out, uint32_t ssrc, std::span<const ReportBlock> blocks);
/// SDES with one chunk holding the CNAME (at most 255 bytes; longer is cut).
void appendCname(std::vector<uint8_t>& out, uint32_t ssrc, const std::string& cname);
void appendBye(std::vector<uint8_t>& out, uint32_t ssrc);
/// A generic NACK for `seqs` (any order; duplicates merged); packed into
/// PID/BLP entries, each covering a PID and the 16 sequence numbers after it.
/// Nothing is appended when `seqs` is empty.
void appendNack(std::vector<uint8_t>& out, uint32_t sender_ssrc, uint32_t media_ssrc, std::span<const uint16_t> seqs);
void appendPli(std::vector<uint8_t>& out, uint32_t sender_ssrc, uint32_t media_ssrc);

// --- time (RFC 3550 4, 6.4.1) ---

/// NTP timestamp of a wall-clock time in microseconds since the Unix epoch.
uint64_t ntpFromUnixMicros(uint64_t unix_us);
/// The middle 32 bits of an NTP timestamp (what LSR and the RTT use).
inline uint32_t ntpMiddle(uint64_t ntp) { return static_cast<uint32_t>(ntp >> 16); }
/// Round-trip time from a report block received at `arrival_middle` (the
/// receiver of the block's clock, middle 32 bits): A - LSR - DLSR
/// (RFC 3550 6.4.1), in seconds; nullopt without an LSR or when negative.
std::optional<double> roundTripSeconds(uint32_t arrival_middle, uint32_t lsr, uint32_t dlsr);

/// Reception statistics of one source (RFC 3550 appendix A.1, A.3, A.8).
class ReceiverStats {
 public:
  /// `clock_rate` of the RTP timestamps (90 kHz for video).
  explicit ReceiverStats(uint32_t clock_rate = 90000) : clock_rate_(clock_rate) {}

  /// A packet arrived: its sequence number, RTP timestamp and arrival time
  /// (microseconds of any monotonic clock). Returns false when the sequence
  /// number is not accepted (probation after a jump, A.1).
  bool onPacket(uint16_t seq, uint32_t rtp_timestamp, uint64_t arrival_us);

  /// A sender report from the source arrived at `arrival_us` (for LSR/DLSR).
  void onSenderReport(uint64_t ntp, uint64_t arrival_us);

  /// The report block for this source now (the interval since the previous
  /// call ends here: fraction lost is over it).
  ReportBlock report(uint32_t source_ssrc, uint64_t now_us);

  bool started() const { return received_ > 0; }
  uint32_t extendedHighest() const { return cycles_ + max_seq_; }
  int64_t cumulativeLost() const;
  uint64_t received() const { return received_; }
  /// Jitter in seconds.
  double jitterSeconds() const { return jitter_ / 16.0 / clock_rate_; }

 private:
  void init(uint16_t seq);

  uint32_t clock_rate_;
  uint16_t max_seq_ = 0;
  uint32_t cycles_ = 0;   // shifted count of sequence number cycles
  uint32_t base_seq_ = 0;
  uint32_t bad_seq_ = 0x10001;  // RTP_SEQ_MOD + 1: none
  int probation_ = 0;
  bool seen_ = false;
  uint64_t received_ = 0;
  uint32_t expected_prior_ = 0;
  uint64_t received_prior_ = 0;
  bool have_transit_ = false;
  int64_t transit_ = 0;
  uint32_t jitter_ = 0;  // scaled by 16 (A.8)
  uint32_t lsr_ = 0;
  uint64_t lsr_arrival_us_ = 0;
};

}  // namespace inspect::video::rtcp
