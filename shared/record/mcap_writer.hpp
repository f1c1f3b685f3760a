#pragma once
// MCAP recorder (format: https://mcap.dev/spec, major version 0) and the
// crash repair for its files. See docs/mcap.md.
//
// File layout written: magic, Header, then in the data section every Schema
// and Channel record as it is added (outside chunks) and the messages in
// Chunk records, each followed by one MessageIndex record per channel in it;
// at close: DataEnd (CRC of the data section), the summary (Schema, Channel,
// Statistics, ChunkIndex groups), one SummaryOffset per group, Footer (summary
// CRC), magic.
//
// A chunk is written when its uncompressed records reach `chunk_size`, or
// when the log times in it would span `chunk_max_age_ns` (checked on every
// write and by tick()). After a chunk the stdio buffer is flushed, so a
// SIGKILLed process loses at most the open chunk; repairMcap() then makes the
// file indexed-readable again.
//
// Every public member function of McapWriter is thread-safe.
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <string_view>

namespace google::protobuf {
class Descriptor;
class MessageLite;
}  // namespace google::protobuf

namespace inspect::record {

struct McapWriterOptions {
  std::string compression = "zstd";           // per chunk: "" (none) or "zstd"
  int zstd_level = 1;
  uint64_t chunk_size = 1 << 20;              // uncompressed record bytes that close a chunk
  uint64_t chunk_max_age_ns = 1'000'000'000;  // log-time span that closes a chunk
  bool sync_chunks = false;                   // fdatasync after every chunk (power-loss safety)
  std::string profile;                        // Header.profile ("" = none)
  std::string library;                        // Header.library ("" = "inspect_robot <version>")
};

struct McapWriterStats {
  uint64_t messages = 0;
  uint32_t chunks = 0;               // chunks written so far
  uint64_t file_bytes = 0;           // bytes written to the file so far
  uint64_t uncompressed_bytes = 0;   // chunk record bytes before compression, summed
  uint64_t open_chunk_bytes = 0;     // records waiting in the open chunk
};

class McapWriter {
 public:
  explicit McapWriter(McapWriterOptions options = {});
  ~McapWriter();  // close(); errors are swallowed there, call close() to see them
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  /// Creates (truncates) `path` and writes magic and Header. Throws
  /// std::runtime_error naming the path and the errno text; std::invalid_argument
  /// for an unsupported compression.
  void open(const std::string& path);
  bool isOpen() const;

  /// Ids start at 1 (schema id 0 means "no schema" in MCAP). Records go to the
  /// file at once. Throw std::logic_error when the writer is not open.
  uint16_t addSchema(std::string_view name, std::string_view encoding, std::string_view data);
  uint16_t addChannel(uint16_t schema_id, std::string_view topic, std::string_view message_encoding,
                      const std::map<std::string, std::string>& metadata = {});
  /// Schema "protobuf" for `type` (added once per type: FileDescriptorSet of its
  /// file and every dependency) and a channel with message encoding "protobuf".
  uint16_t addProtobufChannel(const google::protobuf::Descriptor* type, std::string_view topic,
                              const std::map<std::string, std::string>& metadata = {});

  /// One message; the sequence number is the channel's running count from 1.
  /// Times in ns; log time = when received, publish time = when sent.
  /// std::invalid_argument for an unknown channel; std::runtime_error on I/O errors.
  void write(uint16_t channel_id, uint64_t log_time_ns, uint64_t publish_time_ns, std::string_view data);
  void write(uint16_t channel_id, uint64_t log_time_ns, uint64_t publish_time_ns,
             const google::protobuf::MessageLite& message);

  /// Closes the open chunk when its first log time is `chunk_max_age_ns` or
  /// more before `now_ns` (same clock as the log times). Call at least every
  /// 200 ms so that a quiet recording still reaches the disk.
  void tick(uint64_t now_ns);
  /// Writes the open chunk now (nothing when it is empty).
  void flushChunk();
  /// Last chunk, DataEnd, summary, footer; then the file is closed. Idempotent.
  void close();

  McapWriterStats stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Serialized google.protobuf.FileDescriptorSet with the file of `type` and all
/// the files it imports, dependencies first (MCAP "protobuf" schema encoding).
std::string protobufFileDescriptorSet(const google::protobuf::Descriptor* type);

struct McapRepairResult {
  bool was_complete = false;   // footer and magic were there: file left untouched
  uint64_t messages_kept = 0;  // messages in the file afterwards
  uint32_t chunks_kept = 0;
  uint64_t bytes_dropped = 0;  // bytes cut off the end (partial chunk, partial index...)
};

/// Makes a file cut off anywhere (process killed, no footer) indexed-readable,
/// in place: keeps the header and every complete, CRC-valid record of the data
/// section (complete chunks, schemas, channels), rebuilds the message indexes
/// of the last chunk if they were cut, truncates the rest and appends DataEnd,
/// summary and footer, then fdatasyncs. A complete file is left as it is.
/// Throws std::runtime_error when the file cannot be opened or is not MCAP.
McapRepairResult repairMcap(const std::string& path);

}  // namespace inspect::record
