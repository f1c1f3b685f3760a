#include "shared/record/mcap_writer.hpp"

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

namespace inspect::record {
namespace {

using namespace mcap;  // the format's magic, opcodes and record sizes

std::string defaultLibrary() { return "inspect_robot " INSPECT_VERSION; }

uint32_t crc32Update(uint32_t crc, std::string_view bytes) {
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

void putRecord(Buf& b, const ChannelInfo& c) {
  b.record(kChannel, c.id, c.schema_id, c.topic, c.encoding, c.metadata);
}

SchemaInfo parseSchema(Cursor& c) {
  SchemaInfo s;
  c.fields(s.id, s.name, s.encoding, s.data);
  return s;
}

ChannelInfo parseChannel(Cursor& c) {
  ChannelInfo ch;
  c.fields(ch.id, ch.schema_id, ch.topic, ch.encoding, ch.metadata);
  return ch;
}

// The Message Index records after a chunk; `file_offset` is where b's current
// end lands in the file. Fills the chunk's index offsets and length.
void putMessageIndexes(Buf& b, uint64_t file_offset, const MessageIndexes& index, ChunkInfo& chunk) {
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
    if (messages == 0 || log_time < start_time) start_time = log_time;
    if (messages == 0 || log_time > end_time) end_time = log_time;
    ++messages;
    ++channel_counts[channel];
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

std::string decompress(const std::string& compression, std::string_view body, uint64_t size) {
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

}  // namespace

// ---------------------------------------------------------------- writer

struct McapWriter::Impl {
  explicit Impl(McapWriterOptions o) : opt(std::move(o)) {}
  ~Impl() {
    if (file) std::fclose(file);
    ZSTD_freeCCtx(cctx);
  }

  McapWriterOptions opt;
  mutable std::mutex mu;
  std::string path;
  FILE* file = nullptr;
  uint64_t offset = 0;    // bytes written (into stdio's buffer at least)
  uint32_t data_crc = 0;  // CRC32 of those bytes
  Summary summary;
  std::map<uint16_t, uint32_t> sequence;  // last sequence number per channel
  std::map<std::string, uint16_t, std::less<>> protobuf_schemas;
  uint64_t uncompressed_total = 0;
  std::string scratch;  // a serialized message

  // The open chunk.
  Buf records;
  MessageIndexes index;
  uint64_t chunk_start = 0, chunk_end = 0;
  ZSTD_CCtx* cctx = nullptr;
  std::string compressed;

  void requireOpen() const {
    if (!file) throw std::logic_error("mcap: writer is not open");
  }
  [[noreturn]] void ioError(const char* what) const {
    throw std::runtime_error(std::string("mcap: ") + what + " " + path + ": " + std::strerror(errno));
  }
  void emit(std::string_view bytes) {
    if (!bytes.empty() && std::fwrite(bytes.data(), 1, bytes.size(), file) != bytes.size()) ioError("cannot write");
    data_crc = crc32Update(data_crc, bytes);
    offset += bytes.size();
  }

  // A Schema or Channel record: numbered from 1, written, kept for the summary.
  template <class Info>
  uint16_t add(std::map<uint16_t, Info>& by_id, Info info) {
    if (by_id.size() >= 0xFFFF) throw std::length_error("mcap: too many schemas or channels");
    info.id = static_cast<uint16_t>(by_id.size() + 1);
    Buf b;
    putRecord(b, info);
    emit(b.s);
    const uint16_t id = info.id;
    by_id.emplace(id, std::move(info));
    return id;
  }

  uint16_t addSchema(std::string_view name, std::string_view encoding, std::string_view data) {
    requireOpen();
    return add(summary.schemas, SchemaInfo{0, std::string(name), std::string(encoding), std::string(data)});
  }

  uint16_t addChannel(uint16_t schema_id, std::string_view topic, std::string_view encoding,
                      const std::map<std::string, std::string>& metadata) {
    requireOpen();
    if (schema_id != 0 && !summary.schemas.contains(schema_id))
      throw std::invalid_argument("mcap: unknown schema " + std::to_string(schema_id));
    return add(summary.channels, ChannelInfo{0, schema_id, std::string(topic), std::string(encoding), metadata});
  }

  void append(uint16_t channel, uint64_t log_time, uint64_t publish_time, std::string_view data) {
    requireOpen();
    if (!summary.channels.contains(channel)) throw std::invalid_argument("mcap: unknown channel " + std::to_string(channel));
    if (!index.empty() && std::max(chunk_end, log_time) - std::min(chunk_start, log_time) >= opt.chunk_max_age_ns)
      writeChunk();
    chunk_start = index.empty() ? log_time : std::min(chunk_start, log_time);
    chunk_end = index.empty() ? log_time : std::max(chunk_end, log_time);
    index[channel].emplace_back(log_time, records.s.size());
    records.record(kMessage, channel, ++sequence[channel], log_time, publish_time, Raw{data});
    summary.countMessage(channel, log_time);
    if (records.s.size() >= opt.chunk_size) writeChunk();
  }

  // The open chunk, compressed when that saves bytes, then its message indexes.
  void writeChunk() {
    if (index.empty()) return;
    const std::string_view raw = records.s;
    std::string_view body = raw;
    ChunkInfo info;
    if (opt.compression == "zstd") {
      compressed.resize(ZSTD_compressBound(raw.size()));
      const std::size_t n =
          ZSTD_compressCCtx(cctx, compressed.data(), compressed.size(), raw.data(), raw.size(), opt.zstd_level);
      if (!ZSTD_isError(n) && n < raw.size()) {
        body = std::string_view(compressed.data(), n);
        info.compression = "zstd";
      }
    }
    info.start_time = chunk_start;
    info.end_time = chunk_end;
    info.offset = offset;
    info.compressed_size = body.size();
    info.uncompressed_size = raw.size();
    Buf b;
    const auto at = b.begin(kChunk);  // the records follow from `body`
    b.put(chunk_start);
    b.put(chunk_end);
    b.put(info.uncompressed_size);
    b.put(crc32Update(0, raw));
    b.put(info.compression);
    b.put(info.compressed_size);
    b.end(at, body.size());
    emit(b.s);
    emit(body);
    info.length = offset - info.offset;
    b.s.clear();
    putMessageIndexes(b, offset, index, info);
    emit(b.s);
    summary.chunks.push_back(std::move(info));
    uncompressed_total += raw.size();
    records.s.clear();
    index.clear();
    if (std::fflush(file) != 0) ioError("cannot write");
    if (opt.sync_chunks && ::fdatasync(fileno(file)) != 0) ioError("cannot sync");
  }
};

McapWriter::McapWriter(McapWriterOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {}

McapWriter::~McapWriter() {
  try {
    close();
  } catch (const std::exception&) {
    // Destructors do not throw; call close() to see the error.
  }
}

void McapWriter::open(const std::string& path) {
  std::lock_guard lock(impl_->mu);
  Impl& m = *impl_;
  if (m.file) throw std::logic_error("mcap: writer already open on " + m.path);
  if (!m.opt.compression.empty() && m.opt.compression != "zstd")
    throw std::invalid_argument("mcap: unsupported compression '" + m.opt.compression + "' (\"\" or \"zstd\")");
  if (m.opt.compression == "zstd" && !m.cctx) m.cctx = ZSTD_createCCtx();
  m.path = path;
  m.file = std::fopen(path.c_str(), "wb");
  if (!m.file) throw std::runtime_error("mcap: cannot open " + path + ": " + std::strerror(errno));
  m.offset = 0;
  m.data_crc = 0;
  m.summary = Summary{};
  m.sequence.clear();
  m.protobuf_schemas.clear();
  m.uncompressed_total = 0;
  m.records.s.clear();
  m.index.clear();
  Buf b;
  b.put(Raw{kMagic});
  b.record(kHeader, m.opt.profile, m.opt.library.empty() ? defaultLibrary() : m.opt.library);
  m.emit(b.s);
  if (std::fflush(m.file) != 0) m.ioError("cannot write");
}

bool McapWriter::isOpen() const {
  std::lock_guard lock(impl_->mu);
  return impl_->file != nullptr;
}

uint16_t McapWriter::addSchema(std::string_view name, std::string_view encoding, std::string_view data) {
  std::lock_guard lock(impl_->mu);
  return impl_->addSchema(name, encoding, data);
}

uint16_t McapWriter::addChannel(uint16_t schema_id, std::string_view topic, std::string_view message_encoding,
                                const std::map<std::string, std::string>& metadata) {
  std::lock_guard lock(impl_->mu);
  return impl_->addChannel(schema_id, topic, message_encoding, metadata);
}

uint16_t McapWriter::addProtobufChannel(const google::protobuf::Descriptor* type, std::string_view topic,
                                        const std::map<std::string, std::string>& metadata) {
  std::lock_guard lock(impl_->mu);
  Impl& m = *impl_;
  if (!type) throw std::invalid_argument("mcap: null protobuf descriptor");
  auto it = m.protobuf_schemas.find(type->full_name());
  if (it == m.protobuf_schemas.end())
    it = m.protobuf_schemas
             .emplace(type->full_name(), m.addSchema(type->full_name(), "protobuf", protobufFileDescriptorSet(type)))
             .first;
  return m.addChannel(it->second, topic, "protobuf", metadata);
}

void McapWriter::write(uint16_t channel_id, uint64_t log_time_ns, uint64_t publish_time_ns, std::string_view data) {
  std::lock_guard lock(impl_->mu);
  impl_->append(channel_id, log_time_ns, publish_time_ns, data);
}

void McapWriter::write(uint16_t channel_id, uint64_t log_time_ns, uint64_t publish_time_ns,
                       const google::protobuf::MessageLite& message) {
  std::lock_guard lock(impl_->mu);
  impl_->scratch.clear();
  if (!message.SerializeToString(&impl_->scratch))
    throw std::runtime_error("mcap: cannot serialize " + message.GetTypeName());
  impl_->append(channel_id, log_time_ns, publish_time_ns, impl_->scratch);
}

void McapWriter::tick(uint64_t now_ns) {
  std::lock_guard lock(impl_->mu);
  Impl& m = *impl_;
  if (m.file && !m.index.empty() && now_ns >= m.chunk_start && now_ns - m.chunk_start >= m.opt.chunk_max_age_ns)
    m.writeChunk();
}

void McapWriter::flushChunk() {
  std::lock_guard lock(impl_->mu);
  if (impl_->file) impl_->writeChunk();
}

void McapWriter::close() {
  std::lock_guard lock(impl_->mu);
  Impl& m = *impl_;
  if (!m.file) return;
  FILE* f = m.file;
  try {
    m.writeChunk();
    m.emit(m.summary.tail(m.offset, m.data_crc));
    if (std::fflush(f) != 0 || ::fdatasync(fileno(f)) != 0) m.ioError("cannot write");
  } catch (...) {
    std::fclose(f);
    m.file = nullptr;
    throw;
  }
  m.file = nullptr;
  if (std::fclose(f) != 0) m.ioError("cannot close");
}

McapWriterStats McapWriter::stats() const {
  std::lock_guard lock(impl_->mu);
  const Impl& m = *impl_;
  return {m.summary.messages, static_cast<uint32_t>(m.summary.chunks.size()), m.offset, m.uncompressed_total,
          m.records.s.size()};
}

std::string protobufFileDescriptorSet(const google::protobuf::Descriptor* type) {
  if (!type) throw std::invalid_argument("mcap: null protobuf descriptor");
  google::protobuf::FileDescriptorSet set;
  std::set<std::string> seen;
  // Depth first, every file after the files it imports (the import graph is acyclic).
  auto add = [&](auto&& self, const google::protobuf::FileDescriptor* file) -> void {
    if (!seen.insert(file->name()).second) return;
    for (int i = 0; i < file->dependency_count(); ++i) self(self, file->dependency(i));
    file->CopyTo(set.add_file());
  };
  add(add, type->file());
  return set.SerializeAsString();
}

// ---------------------------------------------------------------- repair

namespace {

class File {  // read-write file descriptor; errors throw with the path
 public:
  explicit File(const std::string& path) : path_(path), fd_(::open(path.c_str(), O_RDWR | O_CLOEXEC)) {
    if (fd_ < 0) fail("cannot open");
  }
  ~File() { ::close(fd_); }
  File(const File&) = delete;
  File& operator=(const File&) = delete;

  uint64_t size() const {
    struct stat st {};
    if (::fstat(fd_, &st) != 0) fail("cannot stat");
    return static_cast<uint64_t>(st.st_size);
  }
  // Up to n bytes at `at` (fewer at the end of the file).
  std::string read(uint64_t at, uint64_t n) const {
    std::string s(n, '\0');
    std::size_t done = 0;
    while (done < n) {  // every pass reads more, stops at the end or fails
      const ssize_t r = ::pread(fd_, s.data() + done, n - done, static_cast<off_t>(at + done));
      if (r < 0 && errno == EINTR) continue;
      if (r < 0) fail("cannot read");
      if (r == 0) break;
      done += static_cast<std::size_t>(r);
    }
    s.resize(done);
    return s;
  }
  void write(uint64_t at, std::string_view d) {
    std::size_t done = 0;
    while (done < d.size()) {  // every pass writes more or fails
      const ssize_t r = ::pwrite(fd_, d.data() + done, d.size() - done, static_cast<off_t>(at + done));
      if (r < 0 && errno == EINTR) continue;
      if (r <= 0) fail("cannot write");
      done += static_cast<std::size_t>(r);
    }
  }
  void truncate(uint64_t n) {
    if (::ftruncate(fd_, static_cast<off_t>(n)) != 0) fail("cannot truncate");
  }
  void sync() {
    if (::fdatasync(fd_) != 0) fail("cannot sync");
  }
  [[noreturn]] void fail(const char* what) const {
    throw std::runtime_error(std::string("mcap: ") + what + " " + path_ + ": " + std::strerror(errno));
  }

 private:
  std::string path_;
  int fd_;
};

// Message and chunk counts of a file that ends with footer and magic (from its
// Statistics record; zeros when it has none); nullopt when it does not end so.
std::optional<std::pair<uint64_t, uint32_t>> completeFileCounts(const File& f, uint64_t size) {
  if (size < 2 * kMagic.size() + kFooterRecord) return std::nullopt;
  const std::string end = f.read(size - kFooterRecord - kMagic.size(), kFooterRecord + kMagic.size());
  Cursor c(end);
  uint64_t length = 0, summary_start = 0, offsets_start = 0;
  uint32_t summary_crc = 0;
  const uint8_t op = c.u8();
  c.fields(length, summary_start, offsets_start, summary_crc);
  if (op != kFooter || length != 20 || c.take(kMagic.size()) != kMagic) return std::nullopt;
  const uint64_t summary_end = offsets_start ? offsets_start : size - kFooterRecord - kMagic.size();
  if (summary_start == 0 || summary_start > summary_end) return std::pair<uint64_t, uint32_t>{0, 0};
  const std::string summary = f.read(summary_start, summary_end - summary_start);
  Cursor s(summary);
  while (!s.done()) {  // every record consumes at least 9 bytes
    const uint8_t op = s.u8();
    Cursor rec(s.take(s.u64()));
    if (op != kStatistics) continue;
    uint64_t messages = 0;
    uint16_t schemas = 0;
    uint32_t channels = 0, attachments = 0, metadata = 0, chunks = 0;
    rec.fields(messages, schemas, channels, attachments, metadata, chunks);
    return std::pair<uint64_t, uint32_t>{messages, chunks};
  }
  return std::pair<uint64_t, uint32_t>{0, 0};
}

// Records that may stand in a data section (0x09 attachment, 0x0C metadata,
// 0x80-0xFF extensions); the others end it.
bool dataSectionOp(uint8_t op) {
  return op == kHeader || op == kSchema || op == kChannel || op == kMessage || op == kChunk || op == kMessageIndex ||
         op == 0x09 || op == 0x0C || op >= 0x80;
}

struct ParsedChunk {
  ChunkInfo info;
  MessageIndexes index;
  std::vector<SchemaInfo> schemas;
  std::vector<ChannelInfo> channels;
};

// A complete Chunk record (content only), CRC checked; throws when it is bad.
ParsedChunk parseChunk(std::string_view content, uint64_t offset) {
  ParsedChunk p;
  ChunkInfo& i = p.info;
  Cursor c(content);
  uint32_t crc = 0;
  c.fields(i.start_time, i.end_time, i.uncompressed_size, crc, i.compression, i.compressed_size);
  const std::string raw = decompress(i.compression, c.take(i.compressed_size), i.uncompressed_size);
  if (crc != 0 && crc32Update(0, raw) != crc) throw std::runtime_error("mcap: chunk CRC mismatch");
  i.offset = offset;
  i.length = kRecordPrefix + content.size();
  Cursor r(raw);
  while (!r.done()) {  // every record consumes at least 9 bytes
    const uint64_t at = r.pos();
    const uint8_t op = r.u8();
    Cursor rec(r.take(r.u64()));
    if (op == kSchema) p.schemas.push_back(parseSchema(rec));
    if (op == kChannel) p.channels.push_back(parseChannel(rec));
    if (op == kMessage) {
      uint16_t channel = 0;
      uint32_t sequence = 0;
      uint64_t log_time = 0;
      rec.fields(channel, sequence, log_time);
      p.index[channel].emplace_back(log_time, at);
    }
  }
  return p;
}

// What survives of a data section: everything up to the first record that is
// cut off, corrupt, or belongs to the end of a file (DataEnd, summary, footer).
struct Scan {
  Summary summary;
  bool header_ok = false;
  uint64_t keep = 0;  // bytes kept from the start of the file
  uint32_t crc = 0;   // CRC32 of those bytes
  MessageIndexes last_index;  // of the last chunk kept
  bool rebuild_last_index = false;
};

Scan scanDataSection(const File& f, uint64_t size) {
  Scan scan;
  uint64_t pos = kMagic.size();
  uint32_t crc = crc32Update(0, kMagic);
  constexpr std::size_t kNone = SIZE_MAX;
  std::size_t open_chunk = kNone;  // chunk whose message indexes may follow
  uint64_t chunk_end = 0;
  uint32_t chunk_end_crc = 0;
  while (pos + kRecordPrefix <= size) {  // pos grows by a whole record every pass
    const std::string prefix_bytes = f.read(pos, kRecordPrefix);
    Cursor prefix(prefix_bytes);
    const uint8_t op = prefix.u8();
    const uint64_t len = prefix.u64();
    if (len > size - pos - kRecordPrefix) break;  // cut off
    if (!scan.header_ok && op != kHeader) break;
    if (!dataSectionOp(op)) break;  // zeros (a lost tail), or the file's end as a killed close() left it
    const std::string rec = f.read(pos, kRecordPrefix + len);
    Cursor c(std::string_view(rec).substr(kRecordPrefix));
    try {
      if (op != kMessageIndex) open_chunk = kNone;
      if (op == kHeader) {
        if (scan.header_ok) break;
        scan.header_ok = true;
      } else if (op == kSchema) {
        SchemaInfo s = parseSchema(c);
        if (s.id != 0) scan.summary.schemas.emplace(s.id, std::move(s));
      } else if (op == kChannel) {
        ChannelInfo ch = parseChannel(c);
        scan.summary.channels.emplace(ch.id, std::move(ch));
      } else if (op == kMessage) {  // outside a chunk: counted, not indexed
        uint16_t channel = 0;
        uint32_t sequence = 0;
        uint64_t log_time = 0;
        c.fields(channel, sequence, log_time);
        scan.summary.countMessage(channel, log_time);
      } else if (op == kChunk) {
        ParsedChunk p = parseChunk(std::string_view(rec).substr(kRecordPrefix), pos);
        for (SchemaInfo& s : p.schemas)
          if (s.id != 0) scan.summary.schemas.emplace(s.id, std::move(s));
        for (ChannelInfo& ch : p.channels) scan.summary.channels.emplace(ch.id, std::move(ch));
        for (const auto& [channel, entries] : p.index)
          for (const auto& entry : entries) scan.summary.countMessage(channel, entry.first);
        scan.summary.chunks.push_back(std::move(p.info));
        scan.last_index = std::move(p.index);
        open_chunk = scan.summary.chunks.size() - 1;
      } else if (op == kMessageIndex && open_chunk != kNone) {
        ChunkInfo& chunk = scan.summary.chunks[open_chunk];
        chunk.index_offsets[c.u16()] = pos;
        chunk.index_length += rec.size();
      }  // anything else (attachment, metadata, extensions) is kept as it is, not indexed
    } catch (const std::exception&) {
      break;  // a corrupt record: the data ends before it
    }
    crc = crc32Update(crc, rec);
    pos += rec.size();
    if (op == kChunk) {
      chunk_end = pos;
      chunk_end_crc = crc;
    }
  }
  scan.keep = scan.header_ok ? pos : 0;
  scan.crc = scan.header_ok ? crc : 0;
  // The last chunk's message indexes cut off: drop them and write them anew.
  if (open_chunk != kNone && scan.summary.chunks[open_chunk].index_offsets.size() != scan.last_index.size()) {
    ChunkInfo& chunk = scan.summary.chunks[open_chunk];
    chunk.index_offsets.clear();
    chunk.index_length = 0;
    scan.keep = chunk_end;
    scan.crc = chunk_end_crc;
    scan.rebuild_last_index = true;
  }
  return scan;
}

}  // namespace

McapRepairResult repairMcap(const std::string& path) {
  File f(path);
  const uint64_t size = f.size();
  const std::string head = f.read(0, kMagic.size());
  if (head != kMagic.substr(0, head.size())) throw std::runtime_error("mcap: " + path + " is not an MCAP file");
  McapRepairResult result;
  if (const auto counts = completeFileCounts(f, size)) {
    result.was_complete = true;
    std::tie(result.messages_kept, result.chunks_kept) = *counts;
    return result;
  }
  Scan scan = scanDataSection(f, size);
  Buf out;  // data-section bytes to append after what is kept
  if (!scan.header_ok) {
    out.put(Raw{kMagic});
    out.record(kHeader, std::string_view(), defaultLibrary());
  }
  if (scan.rebuild_last_index) putMessageIndexes(out, scan.keep, scan.last_index, scan.summary.chunks.back());
  const uint32_t crc = crc32Update(scan.crc, out.s);
  out.put(Raw{scan.summary.tail(scan.keep + out.s.size(), crc)});
  f.truncate(scan.keep);
  f.write(scan.keep, out.s);
  f.sync();
  result.messages_kept = scan.summary.messages;
  result.chunks_kept = static_cast<uint32_t>(scan.summary.chunks.size());
  result.bytes_dropped = size - scan.keep;
  return result;
}

}  // namespace inspect::record
