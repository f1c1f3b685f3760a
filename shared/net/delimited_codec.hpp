#pragma once
// Protobuf delimited framing (varint length + message bytes) for the TCP link.
// Holds no socket: bytes in, frames out; unit-tested on byte vectors.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace google::protobuf {
class MessageLite;
}

namespace inspect::net {

/// Default hard maximum of one frame's message bytes.
inline constexpr std::size_t kDefaultMaxFrame = 1u << 20;

/// Appends `msg` in delimited form to `out`. Returns false if it does not serialise.
bool appendDelimited(const google::protobuf::MessageLite& msg, std::string& out);

/// Incremental parser of delimited frames.
class DelimitedDecoder {
 public:
  enum class Status { kNeedMore, kFrame, kInvalid };

  explicit DelimitedDecoder(std::size_t max_frame = kDefaultMaxFrame) : max_frame_(max_frame) {}

  /// Appends received bytes to the internal buffer.
  void append(std::span<const uint8_t> bytes);
  void append(const char* data, std::size_t n) { append({reinterpret_cast<const uint8_t*>(data), n}); }

  /// Extracts the next frame: kFrame sets `frame` to its message bytes (valid
  /// until the next call); kInvalid means the stream is broken (see error()),
  /// after which the connection must be closed.
  Status next(std::span<const uint8_t>& frame);

  /// Parses the frame returned by next() into `msg`. False if malformed.
  static bool parse(std::span<const uint8_t> frame, google::protobuf::MessageLite& msg);

  const std::string& error() const { return error_; }
  std::size_t buffered() const { return buf_.size() - pos_; }
  std::size_t maxFrame() const { return max_frame_; }

 private:
  std::size_t max_frame_;
  std::vector<uint8_t> buf_;
  std::size_t pos_ = 0;
  std::string error_;
};

}  // namespace inspect::net
