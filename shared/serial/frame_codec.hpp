#pragma once
// Serial frame codec: message <-> COBS frame with id, sequence number and CRC.
// No I/O and no allocation; shared by robot_client and mcu_sim.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "shared/serial/cobs.hpp"
#include "shared/serial/messages.hpp"

namespace inspect::serial {

/// One frame ready for the wire: COBS bytes followed by the 0x00 delimiter.
struct EncodedFrame {
  std::array<uint8_t, kMaxEncodedFrame + 1> bytes{};
  std::size_t size = 0;
  uint8_t seq = 0;  // sequence number given to this frame
  std::span<const uint8_t> span() const { return {bytes.data(), size}; }
};

/// Encodes messages into frames; keeps one sequence counter per message id.
class FrameEncoder {
 public:
  EncodedFrame encode(const Message& msg);

 private:
  std::array<uint8_t, 256> next_seq_{};
};

/// Why a frame was dropped (also the counter it went to).
enum class FrameError { kNone, kBadCobs, kBadCrc, kBadLength, kUnknownId, kOverflow };

/// Decoder statistics.
struct DecoderCounters {
  uint64_t frames_ok = 0;
  uint64_t bad_cobs = 0;
  uint64_t bad_crc = 0;
  uint64_t bad_length = 0;
  uint64_t unknown_id = 0;
  uint64_t seq_gaps = 0;  // frames missing according to sequence numbers
  uint64_t overflow = 0;  // frames dropped for running past kMaxEncodedFrame
  uint64_t bytes_rx = 0;
  uint64_t errors() const { return bad_cobs + bad_crc + bad_length + unknown_id + overflow; }
};

/// Decodes one frame (COBS bytes without delimiter). Returns kNone and fills
/// `msg` and `seq` when it is valid.
FrameError decodeFrame(std::span<const uint8_t> cobs_bytes, Message& msg, uint8_t& seq);

/// The frame layer alone, for a link with messages of its own (the HIL link,
/// shared/hil): [id][seq][payload][CRC-16/CCITT-FALSE], COBS, then 0x00.
EncodedFrame encodeRawFrame(uint8_t id, uint8_t seq, std::span<const uint8_t> payload);
/// A raw frame's parts after decodeRawFrame; `payload` points into `raw`.
struct RawFrame {
  std::array<uint8_t, kMaxRawFrame> raw{};
  uint8_t id = 0;
  uint8_t seq = 0;
  std::span<const uint8_t> payload;
};
/// Checks COBS, length and CRC of one frame (COBS bytes without delimiter):
/// kNone with `out` filled, or kBadCobs, kBadLength, kBadCrc.
FrameError decodeRawFrame(std::span<const uint8_t> cobs_bytes, RawFrame& out);

/// Splits a byte stream at the 0x00 delimiters, in any split: on_frame(cobs
/// bytes) for each non-empty frame; a frame longer than kMaxEncodedFrame is
/// dropped whole and given as on_overflow().
class FrameAssembler {
 public:
  template <class F, class G>
  void feed(std::span<const uint8_t> bytes, F&& on_frame, G&& on_overflow) {
    for (uint8_t b : bytes) {
      if (b != 0) {
        if (len_ < buf_.size()) {
          buf_[len_++] = b;
        } else {
          overflowing_ = true;
        }
        continue;
      }
      if (overflowing_) {
        on_overflow();
      } else if (len_ > 0) {
        on_frame(std::span<const uint8_t>(buf_.data(), len_));
      }
      len_ = 0;
      overflowing_ = false;
    }
  }

 private:
  std::array<uint8_t, kMaxEncodedFrame> buf_{};
  std::size_t len_ = 0;
  bool overflowing_ = false;
};

/// Streaming decoder: accepts bytes in any split, resynchronises on 0x00.
class FrameDecoder {
 public:
  /// Feeds received bytes; calls on_message(const Message&, uint8_t seq) for each valid frame.
  template <class F>
  void feed(std::span<const uint8_t> bytes, F&& on_message) {
    counters_.bytes_rx += bytes.size();
    assembler_.feed(
        bytes,
        [&](std::span<const uint8_t> frame) {
          Message msg;
          uint8_t seq = 0;
          const FrameError err = decodeFrame(frame, msg, seq);
          if (accept(err, msg, seq)) on_message(msg, seq);
        },
        [&] { ++counters_.overflow; });
  }
  const DecoderCounters& counters() const { return counters_; }
  /// The reason the most recent bad frame was dropped.
  FrameError lastError() const { return last_error_; }

 private:
  bool accept(FrameError err, const Message& msg, uint8_t seq);
  FrameAssembler assembler_;
  DecoderCounters counters_;
  FrameError last_error_ = FrameError::kNone;
  std::array<int16_t, 256> last_seq_ = [] {
    std::array<int16_t, 256> a{};
    a.fill(-1);
    return a;
  }();
};

/// Human-readable name of a FrameError.
const char* toString(FrameError e);

}  // namespace inspect::serial
