#pragma once
// The MCAP records as this project writes and repairs them (docs/mcap.md):
// little-endian serialization, a bounds-checked reader, the records' parts
// and the summary section. Internal to shared/record (mcap_writer.cpp,
// mcap_repair.cpp).
#include "shared/record/mcap_format.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vector>

#include <google/protobuf/descriptor.h>
#include <google/protobuf/descriptor.pb.h>
#include <google/protobuf/message_lite.h>

#ifndef INSPECT_VERSION
#define INSPECT_VERSION "unknown"
#endif

namespace inspect::record::detail {

using namespace mcap;  // the format's magic, opcodes and record sizes

inline std::string defaultLibrary() { return "inspect_robot " INSPECT_VERSION; }

inline uint32_t crc32Update(uint32_t crc, std::string_view bytes) {
  while (!bytes.empty()) {  // zlib takes 32-bit lengths
    const std::size_t n = std::min<std::size_t>(bytes.size(), std::size_t{1} << 30);
    crc = static_cast<uint32_t>(::crc32(crc, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(n)));
    bytes.remove_prefix(n);
  }
  return crc;
}

// Per-channel (log time, offset of the Message record in the uncompressed chunk).
using IndexEntries = std::vector<std::pair<uint64_t, uint64_t>>;

struct Raw {  // bytes written as they are (no length prefix)
  std::string_view v;
};

// Little-endian serialization into a growing byte string. A field's C++ type
// is its MCAP type: uint8/16/32/64_t, String or uint32-prefixed Bytes
// (std::string, std::string_view), Map<string, string>, Map<uint16, uint64>,
// Array<Tuple<uint64, uint64>> (IndexEntries), Raw.
struct Buf {
  std::string s;

  void put(uint8_t v) { s.push_back(static_cast<char>(v)); }
  void put(uint16_t v) { le(v, 2); }
  void put(uint32_t v) { le(v, 4); }
  void put(uint64_t v) { le(v, 8); }
  void put(Raw v) { s.append(v.v); }
  void put(std::string_view v) {
    put(static_cast<uint32_t>(v.size()));
    s.append(v);
  }
  void put(const std::string& v) { put(std::string_view(v)); }
  void put(const std::map<std::string, std::string>& m) {
    const std::size_t at = s.size();
    put(uint32_t{0});
    for (const auto& [k, v] : m) put(k), put(v);
    patch(at, s.size() - at - 4, 4);
  }
  void put(const std::map<uint16_t, uint64_t>& m) {
    put(static_cast<uint32_t>(m.size() * 10));
    for (const auto& [k, v] : m) put(k), put(v);
  }
  void put(const IndexEntries& entries) {
    put(static_cast<uint32_t>(entries.size() * 16));
    for (const auto& [a, b] : entries) put(a), put(b);
  }

  // One whole record: opcode, content length, fields in order.
  template <class... Fields>
  void record(uint8_t op, const Fields&... fields) {
    const std::size_t at = begin(op);
    (put(fields), ...);
    end(at);
  }
  // A record written in two steps: end() writes the content length, counting
  // `extra` bytes the caller writes after this buffer.
  std::size_t begin(uint8_t op) {
    put(op);
    put(uint64_t{0});
    return s.size() - 8;
  }
  void end(std::size_t at, uint64_t extra = 0) { patch(at, s.size() - at - 8 + extra, 8); }

 private:
  void le(uint64_t v, int n) {
    for (int i = 0; i < n; ++i) s.push_back(static_cast<char>(v >> (8 * i)));
  }
  void patch(std::size_t at, uint64_t v, int n) {
    for (int i = 0; i < n; ++i) s[at + i] = static_cast<char>(v >> (8 * i));
  }
};

// Bounds-checked little-endian parsing; throws std::runtime_error past the end.
class Cursor {
 public:
  explicit Cursor(std::string_view d) : d_(d) {}
  explicit Cursor(std::string&&) = delete;  // would view a dead temporary
  uint8_t u8() { return static_cast<uint8_t>(le(1)); }
  uint16_t u16() { return static_cast<uint16_t>(le(2)); }
  uint32_t u32() { return static_cast<uint32_t>(le(4)); }
  uint64_t u64() { return le(8); }
  std::string str() { return std::string(take(u32())); }
  std::string_view take(uint64_t n) {
    if (n > d_.size() - pos_) throw std::runtime_error("mcap: record shorter than its fields");
    const std::string_view v = d_.substr(pos_, n);
    pos_ += n;
    return v;
  }
  // Reads fields in order, each as its C++ type says (see Buf).
  template <class... Fields>
  void fields(Fields&... f) {
    (get(f), ...);
  }
  bool done() const { return pos_ == d_.size(); }
  std::size_t pos() const { return pos_; }

 private:
  void get(uint16_t& v) { v = u16(); }
  void get(uint32_t& v) { v = u32(); }
  void get(uint64_t& v) { v = u64(); }
  void get(std::string& v) { v = str(); }
  void get(std::map<std::string, std::string>& m) {
    Cursor entries(take(u32()));
    while (!entries.done()) {  // every entry consumes at least 8 bytes
      std::string k = entries.str();
      m[std::move(k)] = entries.str();
    }
  }
  uint64_t le(int n) {
    const std::string_view b = take(n);
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= static_cast<uint64_t>(static_cast<uint8_t>(b[i])) << (8 * i);
    return v;
  }
  std::string_view d_;
  std::size_t pos_ = 0;
};

struct SchemaInfo {
  uint16_t id = 0;
  std::string name, encoding, data;
};

struct ChannelInfo {
  uint16_t id = 0, schema_id = 0;
  std::string topic, encoding;
  std::map<std::string, std::string> metadata;
};

struct ChunkInfo {  // what a Chunk Index record says
  uint64_t start_time = 0, end_time = 0, offset = 0, length = 0;
  std::map<uint16_t, uint64_t> index_offsets;
  uint64_t index_length = 0;
  std::string compression;
  uint64_t compressed_size = 0, uncompressed_size = 0;
};

using MessageIndexes = std::map<uint16_t, IndexEntries>;  // by channel

void putRecord(Buf& b, const SchemaInfo& s) { b.record(kSchema, s.id, s.name, s.encoding, s.data); }

inline void putRecord(Buf& b, const ChannelInfo& c) {
  b.record(kChannel, c.id, c.schema_id, c.topic, c.encoding, c.metadata);
}

inline SchemaInfo parseSchema(Cursor& c) {
  SchemaInfo s;
  c.fields(s.id, s.name, s.encoding, s.data);
  return s;
}

inline ChannelInfo parseChannel(Cursor& c) {
  ChannelInfo ch;
  c.fields(ch.id, ch.schema_id, ch.topic, ch.encoding, ch.metadata);
  return ch;
}

// The Message Index records after a chunk; `file_offset` is where b's current
// end lands in the file. Fills the chunk's index offsets and length.
inline void putMessageIndexes(Buf& b, uint64_t file_offset, const MessageIndexes& index, ChunkInfo& chunk) {
  const std::size_t from = b.s.size();
  for (const auto& [channel, entries] : index) {
    chunk.index_offsets[channel] = file_offset + (b.s.size() - from);
    b.record(kMessageIndex, channel, entries);
  }
  chunk.index_length = b.s.size() - from;
}

// What the summary section says; kept up to date while writing or scanning.
struct Summary {
  std::map<uint16_t, SchemaInfo> schemas;
  std::map<uint16_t, ChannelInfo> channels;
  std::vector<ChunkInfo> chunks;
  std::map<uint16_t, uint64_t> channel_counts;
  uint64_t messages = 0, start_time = 0, end_time = 0;

  void countMessage(uint16_t channel, uint64_t log_time) {
    countTime(log_time);
    ++channel_counts[channel];
  }
  /// countMessage without channel_counts (the writer keeps those per channel id).
  void countTime(uint64_t log_time) {
    if (messages == 0 || log_time < start_time) start_time = log_time;
    if (messages == 0 || log_time > end_time) end_time = log_time;
    ++messages;
  }

  // DataEnd, summary, summary offsets, footer and magic after a data section
  // of `data_end` bytes whose CRC32 is `data_crc`.
  std::string tail(uint64_t data_end, uint32_t data_crc) const {
    Buf b;
    b.record(kDataEnd, data_crc);
    const std::size_t summary_start = b.s.size();
    std::vector<std::tuple<uint8_t, uint64_t, uint64_t>> groups;  // opcode, start, length
    auto group = [&](uint8_t op, auto&& put) {
      const std::size_t from = b.s.size();
      put();
      if (b.s.size() > from) groups.emplace_back(op, data_end + from, b.s.size() - from);
    };
    group(kSchema, [&] {
      for (const auto& [id, s] : schemas) putRecord(b, s);
    });
    group(kChannel, [&] {
      for (const auto& [id, c] : channels) putRecord(b, c);
    });
    group(kStatistics, [&] {
      const uint32_t attachments = 0, metadata = 0;
      b.record(kStatistics, messages, static_cast<uint16_t>(schemas.size()), static_cast<uint32_t>(channels.size()),
               attachments, metadata, static_cast<uint32_t>(chunks.size()), start_time, end_time, channel_counts);
    });
    group(kChunkIndex, [&] {
      for (const ChunkInfo& c : chunks)
        b.record(kChunkIndex, c.start_time, c.end_time, c.offset, c.length, c.index_offsets, c.index_length,
                 c.compression, c.compressed_size, c.uncompressed_size);
    });
    const uint64_t offsets_start = data_end + b.s.size();
    for (const auto& [op, start, length] : groups) b.record(kSummaryOffset, op, start, length);
    // Footer by hand: its CRC covers the footer itself up to that field.
    b.put(kFooter);
    b.put(uint64_t{20});
    b.put(data_end + summary_start);
    b.put(offsets_start);
    b.put(crc32Update(0, std::string_view(b.s).substr(summary_start)));
    b.put(Raw{kMagic});
    return std::move(b.s);
  }
};

inline std::string decompress(const std::string& compression, std::string_view body, uint64_t size) {
  if (compression.empty()) {
    if (body.size() != size) throw std::runtime_error("mcap: chunk size mismatch");
    return std::string(body);
  }
  if (compression != "zstd") throw std::runtime_error("mcap: unsupported chunk compression '" + compression + "'");
  std::string out(size, '\0');
  const std::size_t n = ZSTD_decompress(out.data(), out.size(), body.data(), body.size());
  if (ZSTD_isError(n) || n != size) throw std::runtime_error("mcap: bad zstd chunk");
  return out;
}


}  // namespace inspect::record::detail
