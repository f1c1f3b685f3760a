#include "shared/record/mcap_writer.hpp"

#include "shared/record/mcap_records.hpp"

namespace inspect::record {
using namespace detail;
using namespace mcap;

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
  // Per channel id (1..N, index 0 unused), beside the summary's maps: a
  // message looks up vectors, not four maps (at 100 robots' runs the maps'
  // cache misses were 5 % of pc_server's CPU, docs/load.md).
  struct ChannelState {
    uint32_t sequence = 0;          // last sequence number
    uint64_t count = 0;             // messages (summary.channel_counts at close)
    IndexEntries* chunk = nullptr;  // its entries in `index` while the chunk is open
  };
  std::vector<ChannelState> channel_state{1};
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
    const uint16_t id =
        add(summary.channels, ChannelInfo{0, schema_id, std::string(topic), std::string(encoding), metadata});
    channel_state.resize(std::size_t{id} + 1);
    return id;
  }

  void append(uint16_t channel, uint64_t log_time, uint64_t publish_time, std::string_view data) {
    requireOpen();
    if (channel == 0 || channel >= channel_state.size())  // ids are 1..N (add)
      throw std::invalid_argument("mcap: unknown channel " + std::to_string(channel));
    ChannelState& ch = channel_state[channel];
    if (!index.empty() && std::max(chunk_end, log_time) - std::min(chunk_start, log_time) >= opt.chunk_max_age_ns)
      writeChunk();
    chunk_start = index.empty() ? log_time : std::min(chunk_start, log_time);
    chunk_end = index.empty() ? log_time : std::max(chunk_end, log_time);
    if (!ch.chunk) ch.chunk = &index[channel];  // map nodes stay put until index.clear()
    ch.chunk->emplace_back(log_time, records.s.size());
    records.record(kMessage, channel, ++ch.sequence, log_time, publish_time, Raw{data});
    summary.countTime(log_time);
    ++ch.count;
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
    for (auto& ch : channel_state) ch.chunk = nullptr;
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
  m.channel_state.assign(1, {});
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
    for (std::size_t id = 1; id < m.channel_state.size(); ++id)
      if (m.channel_state[id].count > 0) m.summary.channel_counts[static_cast<uint16_t>(id)] = m.channel_state[id].count;
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

}  // namespace inspect::record
