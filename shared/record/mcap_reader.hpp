#pragma once
// MCAP reader for the files McapWriter writes (and other MCAP files with ""
// or "zstd" chunks). See docs/mcap.md.
//
// Reads like a streaming reader, start to end, without the summary: a file
// repaired by repairMcap(), or one cut off by a crash (no footer), still gives
// every complete record; the reading stops cleanly at the first record the
// file ends inside, and truncated() says so. Corrupt content (a chunk whose
// CRC does not match, a record shorter than its fields, an unsupported
// compression) throws instead.
//
// The whole file is held in memory, with the decompressed chunks, for the
// reader's lifetime. Not thread-safe (decode() fills a cache).
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>

namespace google::protobuf {
class Descriptor;
class Message;
}  // namespace google::protobuf

namespace inspect::record {

struct McapSchema {
  uint16_t id = 0;
  std::string name;      // e.g. "inspect.v1.Telemetry"
  std::string encoding;  // e.g. "protobuf"
  std::string data;      // for protobuf: a serialized google.protobuf.FileDescriptorSet
};

struct McapChannel {
  uint16_t id = 0;
  uint16_t schema_id = 0;  // 0 = no schema
  std::string topic;
  std::string schema_name;       // "" when there is no schema (or it is unknown)
  std::string message_encoding;  // e.g. "protobuf"
  std::map<std::string, std::string> metadata;
};

struct McapMessageView {  // valid while the reader lives
  uint16_t channel_id = 0;
  std::string_view topic;  // "" for a channel the file never declared
  uint32_t sequence = 0;
  uint64_t log_time_ns = 0;
  uint64_t publish_time_ns = 0;
  std::string_view data;
};

class McapReader {
 public:
  using Schema = McapSchema;
  using Channel = McapChannel;
  using MessageView = McapMessageView;

  /// Reads the whole file. Throws std::runtime_error naming `path` and the
  /// problem: cannot open or read it, not an MCAP file (magic, no Header),
  /// a record shorter than its fields, chunk or data-section CRC mismatch,
  /// unsupported compression, a chunk that does not decompress to its size.
  static McapReader open(const std::string& path);

  McapReader(McapReader&&) noexcept;
  McapReader& operator=(McapReader&&) noexcept;
  ~McapReader();

  const std::string& path() const;
  const std::map<uint16_t, Schema>& schemas() const;
  const std::map<uint16_t, Channel>& channels() const;
  uint64_t messageCount() const;
  /// Messages per channel id.
  const std::map<uint16_t, uint64_t>& channelMessageCounts() const;
  uint32_t chunkCount() const;

  /// The file ends before its footer and end magic: inside a record (which
  /// was dropped) or right after one without a DataEnd, or in the summary.
  bool truncated() const;
  /// Where the complete records of the data section end (file size when the
  /// data section ended with DataEnd).
  uint64_t completeBytes() const;

  /// Every message in file order (chunks in order, messages in each chunk in
  /// the order written); stops early when `fn` returns false.
  void forEach(const std::function<bool(const MessageView&)>& fn) const;

  /// The message type of a channel whose schema is a protobuf
  /// FileDescriptorSet (built once per schema into a pool of the reader's);
  /// nullptr for any other channel. Valid while the reader lives.
  const google::protobuf::Descriptor* descriptor(uint16_t channel_id) const;
  /// The message parsed as a dynamic message of its channel's schema (no
  /// compiled types needed). Must not outlive the reader. Throws
  /// std::runtime_error when the channel is not protobuf, its schema does not
  /// build, or the data does not parse.
  std::unique_ptr<google::protobuf::Message> decode(const MessageView& message) const;

 private:
  struct Impl;
  explicit McapReader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace inspect::record
