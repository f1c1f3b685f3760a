#pragma once
// H.264 over RTP (RFC 6184, RFC 3550): packetizer for the robot, reorder
// buffer and depacketizer for the server. Pure byte work: no sockets, no
// clocks, no codec. docs/video.md has the wire details.
//
// - Packetization mode 1 (non-interleaved): a NAL unit that fits the payload
//   budget goes as a single-NAL-unit packet, a larger one as FU-A fragments.
//   STAP-A is understood on receive.
// - Payload type 96, 90 kHz timestamps, the marker bit on the last packet of
//   an access unit (a frame).
// - Each frame's capture time travels in an RFC 8285 one-byte header
//   extension (profile 0xBEDE) on the frame's first packet: element id 1,
//   8 bytes, microseconds of the sender's capture clock, big-endian.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace inspect::video {

inline constexpr uint8_t kPayloadType = 96;
inline constexpr uint32_t kClockRate = 90000;
inline constexpr uint8_t kCaptureTimeExtId = 1;
inline constexpr std::size_t kRtpHeaderSize = 12;

/// NAL unit types used here (ITU-T H.264 Table 7-1, RFC 6184 5.2).
enum NalType : uint8_t {
  kNalSlice = 1,
  kNalIdr = 5,
  kNalSei = 6,
  kNalSps = 7,
  kNalPps = 8,
  kNalAud = 9,
  kNalStapA = 24,
  kNalFuA = 28,
};
inline uint8_t nalType(uint8_t header) { return header & 0x1F; }

/// The NAL units of an Annex B byte stream (start codes 00 00 01 / 00 00 00 01
/// removed); empty units are skipped. Views into `annexb`.
std::vector<std::span<const uint8_t>> splitAnnexB(std::span<const uint8_t> annexb);

/// A parsed RTP packet (views into the datagram).
struct RtpPacket {
  uint8_t payload_type = 0;
  bool marker = false;
  uint16_t seq = 0;
  uint32_t timestamp = 0;
  uint32_t ssrc = 0;
  std::optional<uint64_t> capture_us;  // from the header extension, when present
  std::span<const uint8_t> payload;
};

/// Why a datagram was not an RTP packet we accept.
enum class RtpError { kNone, kTooShort, kBadVersion, kBadCsrc, kBadExtension, kBadPadding };
const char* toString(RtpError e);

/// Parses an RTP datagram (RFC 3550 5.1; CSRCs skipped; padding removed).
RtpError parseRtp(std::span<const uint8_t> datagram, RtpPacket& out);

/// Splits encoded frames into RTP packets.
class H264Packetizer {
 public:
  /// `max_payload` is the RTP payload budget per packet (MTU minus IP/UDP/RTP
  /// headers and the extension); at least 64.
  H264Packetizer(uint32_t ssrc, std::size_t max_payload, uint16_t first_seq = 0);

  /// Packetizes one access unit (Annex B) with its 90 kHz timestamp and
  /// capture time; appends each datagram to `out`. Returns the packets added.
  std::size_t packetize(std::span<const uint8_t> annexb, uint32_t timestamp, uint64_t capture_us,
                        std::vector<std::vector<uint8_t>>& out);

  uint16_t nextSeq() const { return seq_; }
  uint32_t ssrc() const { return ssrc_; }
  std::size_t maxPayload() const { return max_payload_; }

 private:
  void emit(std::vector<std::vector<uint8_t>>& out, bool marker, uint32_t ts, const uint64_t* capture_us,
            std::span<const uint8_t> a, std::span<const uint8_t> b = {});
  uint32_t ssrc_;
  std::size_t max_payload_;
  uint16_t seq_;
};

/// Holds packets briefly so that reordered ones can be put back in sequence.
/// Packets are released in sequence order; a gap is given up (released past)
/// when the buffer holds more than `window` packets. Duplicates and packets
/// older than what was already released are dropped and counted.
class ReorderBuffer {
 public:
  explicit ReorderBuffer(std::size_t window = 16) : window_(window) {}

  /// Adds a datagram with its sequence number; returns false if dropped.
  bool push(uint16_t seq, std::vector<uint8_t> datagram);
  /// Moves the packets that are ready, in order, into `out` (appended).
  /// Each released packet is preceded by the number of sequence numbers
  /// skipped before it (0 normally).
  void pop(std::vector<std::pair<uint32_t, std::vector<uint8_t>>>& out);
  /// Releases everything held (gaps included), e.g. after a pause.
  void flush(std::vector<std::pair<uint32_t, std::vector<uint8_t>>>& out);
  /// Gives up the first gap only: releases the first packet held (the
  /// missing ones before it reported skipped) and those in order after it.
  void skipGap(std::vector<std::pair<uint32_t, std::vector<uint8_t>>>& out);

  uint64_t duplicates() const { return duplicates_; }
  uint64_t late() const { return late_; }
  std::size_t held() const { return held_.size(); }
  /// The next sequence number to release (meaningful once a packet came).
  uint16_t next() const { return next_; }

 private:
  // Releases the first packet held, with how many were skipped before it.
  void releaseFront(std::vector<std::pair<uint32_t, std::vector<uint8_t>>>& out);
  std::size_t window_;
  bool started_ = false;
  uint16_t next_ = 0;  // the next sequence number to release
  std::vector<std::pair<uint16_t, std::vector<uint8_t>>> held_;  // sorted by distance from next_
  uint64_t duplicates_ = 0;
  uint64_t late_ = 0;
};

/// One reassembled access unit.
struct Frame {
  uint32_t timestamp = 0;
  std::optional<uint64_t> capture_us;
  std::vector<uint8_t> annexb;  // NAL units with 4-byte start codes
  bool keyframe = false;        // contains an IDR slice
  bool has_parameter_sets = false;  // contains SPS and PPS
};

struct DepacketizerCounters {
  uint64_t packets = 0;
  uint64_t frames = 0;
  uint64_t frames_dropped = 0;    // incomplete (a packet lost) or corrupt
  uint64_t lost_packets = 0;      // sequence numbers never seen
  uint64_t bad_payload = 0;       // unknown NAL type, malformed FU-A/STAP-A, a start code inside a NAL unit
};

/// Rebuilds access units from in-order packets (ReorderBuffer output).
class H264Depacketizer {
 public:
  /// One in-order packet; `skipped` = sequence numbers lost just before it.
  /// Returns a frame when this packet (its marker bit) completes an intact
  /// one. A frame with a loss anywhere in it (or whose marker packet never
  /// came) is dropped.
  std::optional<Frame> push(const RtpPacket& p, uint32_t skipped);

  const DepacketizerCounters& counters() const { return c_; }
  /// True after a frame was dropped until the next keyframe arrives: the
  /// decoder's picture is damaged, a keyframe should be requested.
  bool needKeyframe() const { return need_keyframe_; }

 private:
  std::optional<Frame> finish();
  void appendNal(std::span<const uint8_t> nal);
  void noteType(uint8_t nal_type);

  DepacketizerCounters c_;
  Frame cur_;
  bool have_cur_ = false;
  bool cur_sps_ = false, cur_pps_ = false;
  bool cur_broken_ = false;
  bool in_fu_ = false;
  std::size_t fu_start_ = 0;  // where the FU-A's NAL unit begins in cur_.annexb
  bool need_keyframe_ = true;  // nothing decodable before the first keyframe
};

}  // namespace inspect::video
