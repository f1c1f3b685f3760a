// Fuzzes the serial codec (shared/serial): COBS, frame decoding with its CRC,
// and the streaming decoder fed the input in arbitrary chunks.
//
// Input: byte 0 seeds the chunk sizes; the rest is the serial byte stream.
// Invariants checked:
// - COBS: encode then decode gives the bytes back (inputs <= 254 bytes); a
//   decoded frame is at most 254 bytes and re-encodes to something that
//   decodes to the same bytes;
// - the streaming decoder gives the same messages, sequence numbers and
//   counters whether the stream arrives in one piece or in chunks;
// - every message it accepts re-encodes into a frame that decodes to it.
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "shared/serial/cobs.hpp"
#include "shared/serial/frame_codec.hpp"
#include "tests/fuzz/fuzz_records.hpp"

using namespace inspect::serial;

namespace {

struct Received {
  std::vector<Message> msgs;
  std::vector<uint8_t> seqs;
};

bool sameCounters(const DecoderCounters& a, const DecoderCounters& b) {
  return a.frames_ok == b.frames_ok && a.bad_cobs == b.bad_cobs && a.bad_crc == b.bad_crc &&
         a.bad_length == b.bad_length && a.unknown_id == b.unknown_id && a.seq_gaps == b.seq_gaps &&
         a.overflow == b.overflow && a.bytes_rx == b.bytes_rx;
}

void checkCobs(std::span<const uint8_t> in) {
  std::array<uint8_t, kMaxRawFrame> raw{};
  std::array<uint8_t, kMaxEncodedFrame> enc{};
  std::array<uint8_t, kMaxRawFrame> back{};
  // Arbitrary bytes as one COBS frame.
  if (const auto n = cobsDecode(in, raw)) {
    FUZZ_CHECK(*n <= kMaxRawFrame);
    const std::size_t e = cobsEncode({raw.data(), *n}, enc);
    FUZZ_CHECK(e == *n + 1);
    FUZZ_CHECK(std::find(enc.begin(), enc.begin() + e, 0) == enc.begin() + e);  // no zero inside a frame
    const auto m = cobsDecode({enc.data(), e}, back);
    FUZZ_CHECK(m && *m == *n && std::equal(back.begin(), back.begin() + *n, raw.begin()));
  }
  // Arbitrary bytes as a payload.
  if (in.size() <= kMaxRawFrame) {
    const std::size_t e = cobsEncode(in, enc);
    FUZZ_CHECK(e == in.size() + 1);
    FUZZ_CHECK(std::find(enc.begin(), enc.begin() + e, 0) == enc.begin() + e);
    const auto m = cobsDecode({enc.data(), e}, back);
    FUZZ_CHECK(m && *m == in.size() && std::equal(in.begin(), in.end(), back.begin()));
  } else {
    FUZZ_CHECK(cobsEncode(in, enc) == 0);
  }
  // Too small an output buffer is refused, never overrun.
  std::array<uint8_t, 8> tiny{};
  (void)cobsDecode(in, tiny);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  uint32_t rng = data[0] * 2654435761u + 1;
  const std::span<const uint8_t> stream(data + 1, size - 1);

  // Each 0x00-delimited piece as one COBS frame, and through decodeFrame.
  std::size_t start = 0;
  for (std::size_t i = 0; i <= stream.size(); ++i) {
    if (i < stream.size() && stream[i] != 0) continue;
    const auto piece = stream.subspan(start, i - start);
    checkCobs(piece);
    Message m;
    uint8_t seq = 0;
    (void)decodeFrame(piece, m, seq);
    start = i + 1;
  }

  // The whole stream at once, then in chunks: same result.
  FrameDecoder whole, chunked;
  Received a, b;
  whole.feed(stream, [&](const Message& m, uint8_t s) {
    a.msgs.push_back(m);
    a.seqs.push_back(s);
  });
  std::size_t pos = 0;
  while (pos < stream.size()) {
    rng = rng * 1103515245u + 12345u;
    const std::size_t n = std::min<std::size_t>(stream.size() - pos, 1 + (rng >> 16) % 300);
    chunked.feed(stream.subspan(pos, n), [&](const Message& m, uint8_t s) {
      b.msgs.push_back(m);
      b.seqs.push_back(s);
    });
    pos += n;
  }
  FUZZ_CHECK(a.msgs == b.msgs && a.seqs == b.seqs);
  FUZZ_CHECK(sameCounters(whole.counters(), chunked.counters()));
  FUZZ_CHECK(whole.counters().bytes_rx == stream.size());
  const auto zeros = static_cast<uint64_t>(std::count(stream.begin(), stream.end(), 0));
  FUZZ_CHECK(whole.counters().frames_ok + whole.counters().errors() <= zeros);
  FUZZ_CHECK(whole.counters().frames_ok == a.msgs.size());

  // Every accepted message survives a round trip through the encoder.
  FrameEncoder enc;
  for (const auto& m : a.msgs) {
    const EncodedFrame f = enc.encode(m);
    FUZZ_CHECK(f.size >= 2 && f.bytes[f.size - 1] == 0);
    Message back;
    uint8_t seq = 0;
    FUZZ_CHECK(decodeFrame({f.bytes.data(), f.size - 1}, back, seq) == FrameError::kNone);
    FUZZ_CHECK(back == m && seq == f.seq);
  }
  return 0;
}
