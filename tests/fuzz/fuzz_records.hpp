#pragma once
// The input layout of the record-driven harnesses (fuzz_link_server,
// fuzz_robot_core, fuzz_rtp_h264): a sequence of records
//   [tag: 1 byte][length: 2 bytes, little-endian][length bytes of body]
// A truncated last record takes whatever is left, so every byte string is a
// valid input and mutations of lengths or bodies stay meaningful.
// make_seeds.cpp writes seed files in this layout.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <span>
#include <string>
#include <vector>

namespace inspect::fuzz {

struct Record {
  uint8_t tag = 0;
  std::span<const uint8_t> body;
};

class RecordReader {
 public:
  RecordReader(const uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool next(Record& r) {
    if (pos_ + 3 > size_) return false;
    r.tag = data_[pos_];
    std::size_t len = static_cast<std::size_t>(data_[pos_ + 1]) | static_cast<std::size_t>(data_[pos_ + 2]) << 8;
    pos_ += 3;
    if (len > size_ - pos_) len = size_ - pos_;
    r.body = {data_ + pos_, len};
    pos_ += len;
    return true;
  }

 private:
  const uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

/// Appends one record (bodies over 65535 bytes are the writer's bug).
inline void putRecord(std::vector<uint8_t>& out, uint8_t tag, std::span<const uint8_t> body) {
  out.push_back(tag);
  out.push_back(static_cast<uint8_t>(body.size()));
  out.push_back(static_cast<uint8_t>(body.size() >> 8));
  out.insert(out.end(), body.begin(), body.end());
}
inline void putRecord(std::vector<uint8_t>& out, uint8_t tag, const std::string& body) {
  putRecord(out, tag, {reinterpret_cast<const uint8_t*>(body.data()), body.size()});
}

/// Reports a broken invariant the way libFuzzer reports a crash (with the input saved).
[[noreturn]] inline void fail(const char* what) {
  std::fprintf(stderr, "fuzz invariant broken: %s\n", what);
  std::abort();
}
#define FUZZ_CHECK(cond) \
  do {                   \
    if (!(cond)) ::inspect::fuzz::fail(#cond " (" __FILE__ ")"); \
  } while (0)

}  // namespace inspect::fuzz
