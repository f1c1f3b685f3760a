#include "shared/net/delimited_codec.hpp"

#include <google/protobuf/message_lite.h>

namespace inspect::net {

bool appendDelimited(const google::protobuf::MessageLite& msg, std::string& out) {
  const std::size_t n = msg.ByteSizeLong();
  uint64_t v = n;
  while (v >= 0x80) {
    out.push_back(static_cast<char>((v & 0x7F) | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<char>(v));
  const std::size_t at = out.size();
  out.resize(at + n);
  return msg.SerializeToArray(out.data() + at, static_cast<int>(n));
}

void DelimitedDecoder::append(std::span<const uint8_t> bytes) {
  // Compact once the consumed prefix dominates, so the buffer does not grow without bound.
  if (pos_ > 0 && pos_ * 2 >= buf_.size()) {
    buf_.erase(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(pos_));
    pos_ = 0;
  }
  buf_.insert(buf_.end(), bytes.begin(), bytes.end());
}

DelimitedDecoder::Status DelimitedDecoder::next(std::span<const uint8_t>& frame) {
  if (!error_.empty()) return Status::kInvalid;
  uint64_t len = 0;
  std::size_t i = pos_;
  int shift = 0;
  for (;;) {
    if (i >= buf_.size()) return Status::kNeedMore;
    const uint8_t b = buf_[i++];
    if (shift >= 63 || (shift == 56 && b > 0x7F)) {
      error_ = "length varint longer than 64 bits";
      return Status::kInvalid;
    }
    len |= static_cast<uint64_t>(b & 0x7F) << shift;
    if (!(b & 0x80)) break;
    shift += 7;
    if (i - pos_ > 10) {
      error_ = "length varint longer than 10 bytes";
      return Status::kInvalid;
    }
  }
  if (len > max_frame_) {
    error_ = "frame of " + std::to_string(len) + " bytes exceeds the maximum of " + std::to_string(max_frame_);
    return Status::kInvalid;
  }
  if (buf_.size() - i < len) return Status::kNeedMore;
  frame = {buf_.data() + i, static_cast<std::size_t>(len)};
  pos_ = i + static_cast<std::size_t>(len);
  return Status::kFrame;
}

bool DelimitedDecoder::parse(std::span<const uint8_t> frame, google::protobuf::MessageLite& msg) {
  return msg.ParseFromArray(frame.data(), static_cast<int>(frame.size()));
}

}  // namespace inspect::net
