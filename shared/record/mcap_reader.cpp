#include "shared/record/mcap_reader.hpp"

#include "shared/record/mcap_format.hpp"

#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <deque>
#include <stdexcept>
#include <utility>
#include <vector>

#include <google/protobuf/descriptor.h>
#include <google/protobuf/descriptor.pb.h>
#include <google/protobuf/dynamic_message.h>

namespace inspect::record {
namespace {

namespace pb = google::protobuf;

using namespace mcap;  // the format's magic, opcodes and record sizes
constexpr uint64_t kMaxChunk = uint64_t{1} << 34;  // a larger uncompressed size is taken for corruption

uint32_t crcOf(std::string_view s) {
  uLong crc = 0;
  for (std::size_t i = 0; i < s.size();) {  // zlib takes 32-bit lengths; i grows every pass
    const auto n = static_cast<uInt>(std::min<std::size_t>(s.size() - i, std::size_t{1} << 30));
    crc = ::crc32(crc, reinterpret_cast<const Bytef*>(s.data() + i), n);
    i += n;
  }
  return static_cast<uint32_t>(crc);
}

// Little-endian fields taken from the front of a record's content.
struct In {
  std::string_view s;

  std::string_view take(uint64_t n) {
    if (n > s.size()) throw std::runtime_error("record shorter than its fields");
    const std::string_view v = s.substr(0, n);
    s.remove_prefix(n);
    return v;
  }
  uint64_t num(int bytes) {
    const std::string_view b = take(bytes);
    uint64_t v = 0;
    for (int i = bytes; i-- > 0;) v = v << 8 | static_cast<uint8_t>(b[i]);
    return v;
  }
  uint16_t u16() { return static_cast<uint16_t>(num(2)); }
  uint32_t u32() { return static_cast<uint32_t>(num(4)); }
  uint64_t u64() { return num(8); }
  std::string text() { return std::string(take(u32())); }
  std::map<std::string, std::string> strings() {
    In m{take(u32())};
    std::map<std::string, std::string> out;
    while (!m.s.empty()) {  // every entry takes at least 8 bytes
      std::string k = m.text();
      out[std::move(k)] = m.text();
    }
    return out;
  }
  // A record prefix at the front, or nullopt-like false when `s` ends inside
  // the record (op and content then untouched).
  bool record(uint8_t& op, In& content) {
    if (s.size() < kRecordPrefix) return false;
    In p{s.substr(0, kRecordPrefix)};
    const auto o = static_cast<uint8_t>(p.num(1));
    const uint64_t len = p.u64();
    if (len > s.size() - kRecordPrefix) return false;
    op = o;
    content = In{s.substr(kRecordPrefix, len)};
    s.remove_prefix(kRecordPrefix + len);
    return true;
  }
};

struct Entry {
  uint16_t channel;
  uint32_t sequence;
  uint64_t log, publish;
  std::string_view data;
};

struct Decoder {  // one per protobuf schema; the factory goes before the pool it uses
  std::unique_ptr<pb::DescriptorPool> pool;
  std::unique_ptr<pb::DynamicMessageFactory> factory;
  const pb::Descriptor* type = nullptr;
  std::string error;  // why type is null
};

}  // namespace

struct McapReader::Impl {
  std::string path;
  std::string file;
  std::deque<std::string> inflated;  // decompressed chunks (stable addresses)
  std::map<uint16_t, Schema> schemas;
  std::map<uint16_t, Channel> channels;
  std::vector<Entry> messages;
  std::map<uint16_t, uint64_t> counts;
  uint32_t chunks = 0;
  bool truncated = false;
  uint64_t complete = 0;
  uint64_t at = 0;  // offset of the record being read, for errors
  std::map<uint16_t, Decoder> decoders;  // by schema id

  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error("mcap: " + path + ": " + what + " (record at offset " + std::to_string(at) + ")");
  }

  void load() {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) throw std::runtime_error("mcap: cannot open " + path + ": " + std::strerror(errno));
    char buf[1 << 16];
    std::size_t n = 0;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) file.append(buf, n);  // ends at EOF or error
    const bool bad = std::ferror(f);
    std::fclose(f);
    if (bad) throw std::runtime_error("mcap: cannot read " + path + ": " + std::strerror(errno));
  }

  // Schema, Channel and Message records (in a chunk or not); others are skipped.
  void record(uint8_t op, In c) {
    if (op == kSchema) {
      Schema s;
      s.id = c.u16();
      s.name = c.text();
      s.encoding = c.text();
      s.data = std::string(c.take(c.u32()));
      if (s.id != 0) schemas.insert_or_assign(s.id, std::move(s));
    } else if (op == kChannel) {
      Channel ch;
      ch.id = c.u16();
      ch.schema_id = c.u16();
      ch.topic = c.text();
      ch.message_encoding = c.text();
      ch.metadata = c.strings();
      channels.insert_or_assign(ch.id, std::move(ch));
    } else if (op == kMessage) {
      Entry e{};
      e.channel = c.u16();
      e.sequence = c.u32();
      e.log = c.u64();
      e.publish = c.u64();
      e.data = c.s;
      messages.push_back(e);
      ++counts[e.channel];
    }
  }

  void chunk(In c) {
    c.take(16);  // message start and end time
    const uint64_t size = c.u64();
    const uint32_t crc = c.u32();
    const std::string compression = c.text();
    const std::string_view body = c.take(c.u64());
    std::string_view raw = body;
    if (compression == "zstd") {
      const unsigned long long framed = ZSTD_getFrameContentSize(body.data(), body.size());
      if (size > kMaxChunk || (framed != ZSTD_CONTENTSIZE_UNKNOWN && framed != size))
        fail("zstd chunk does not decompress to its uncompressed size");
      std::string& out = inflated.emplace_back(size, '\0');
      const std::size_t n = ZSTD_decompress(out.data(), out.size(), body.data(), body.size());
      if (ZSTD_isError(n) || n != size) fail("zstd chunk does not decompress to its uncompressed size");
      raw = out;
    } else if (!compression.empty()) {
      fail("unsupported chunk compression '" + compression + "'");
    } else if (body.size() != size) {
      fail("uncompressed chunk of the wrong size");
    }
    if (crc != 0 && crcOf(raw) != crc) fail("chunk CRC mismatch");
    In records{raw};
    uint8_t op = 0;
    In content;
    while (!records.s.empty()) {  // every pass takes a record or throws
      if (!records.record(op, content)) fail("chunk ends inside a record");
      record(op, content);
    }
    ++chunks;
  }

  void read() {
    if (file.size() < kMagic.size() || std::string_view(file).substr(0, kMagic.size()) != kMagic)
      throw std::runtime_error("mcap: " + path + " is not an MCAP file (no magic)");
    In rest{std::string_view(file).substr(kMagic.size())};
    bool header = false, data_end = false;
    uint8_t op = 0;
    In c;
    for (at = kMagic.size(); !data_end && rest.record(op, c); at = file.size() - rest.s.size()) {  // rest shrinks
      if (!header && op != kHeader) throw std::runtime_error("mcap: " + path + " is not an MCAP file (no Header)");
      header = true;
      if (op == kChunk) {
        chunk(c);
      } else if (op == kDataEnd) {
        const uint32_t crc = c.u32();
        if (crc != 0 && crc != crcOf(std::string_view(file).substr(0, at))) fail("data section CRC mismatch");
        data_end = true;
      } else if (op == kFooter) {  // no DataEnd: the footer ends the data section
        data_end = true;
      } else {
        record(op, c);
      }
    }
    complete = file.size() - rest.s.size();
    truncated = !data_end || !std::string_view(file).ends_with(kMagic) || file.size() < 2 * kMagic.size();
    for (auto& [id, ch] : channels)
      if (const auto s = schemas.find(ch.schema_id); s != schemas.end()) ch.schema_name = s->second.name;
  }

  const Decoder* decoder(uint16_t channel_id) {
    const auto ch = channels.find(channel_id);
    if (ch == channels.end() || ch->second.message_encoding != "protobuf") return nullptr;
    const auto s = schemas.find(ch->second.schema_id);
    if (s == schemas.end() || s->second.encoding != "protobuf") return nullptr;
    auto [it, fresh] = decoders.try_emplace(s->first);
    Decoder& d = it->second;
    if (!fresh) return &d;
    d.pool = std::make_unique<pb::DescriptorPool>();
    pb::FileDescriptorSet set;
    if (!set.ParseFromString(s->second.data)) {
      d.error = "schema " + s->second.name + " is not a FileDescriptorSet";
      return &d;
    }
    for (const pb::FileDescriptorProto& proto : set.file()) {  // dependencies first
      if (!d.pool->BuildFile(proto)) {
        d.error = "schema " + s->second.name + ": cannot build " + proto.name();
        return &d;
      }
    }
    d.type = d.pool->FindMessageTypeByName(s->second.name);
    if (!d.type) d.error = "schema " + s->second.name + " does not define that type";
    d.factory = std::make_unique<pb::DynamicMessageFactory>(d.pool.get());
    return &d;
  }
};

McapReader::McapReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
McapReader::McapReader(McapReader&&) noexcept = default;
McapReader& McapReader::operator=(McapReader&&) noexcept = default;
McapReader::~McapReader() = default;

McapReader McapReader::open(const std::string& path) {
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->load();
  try {
    impl->read();
  } catch (const std::runtime_error& e) {
    if (std::string_view(e.what()).starts_with("mcap: " + path)) throw;
    impl->fail(e.what());  // a parse error from In: name the file and where
  }
  return McapReader(std::move(impl));
}

const std::string& McapReader::path() const { return impl_->path; }
const std::map<uint16_t, McapSchema>& McapReader::schemas() const { return impl_->schemas; }
const std::map<uint16_t, McapChannel>& McapReader::channels() const { return impl_->channels; }
uint64_t McapReader::messageCount() const { return impl_->messages.size(); }
const std::map<uint16_t, uint64_t>& McapReader::channelMessageCounts() const { return impl_->counts; }
uint32_t McapReader::chunkCount() const { return impl_->chunks; }
bool McapReader::truncated() const { return impl_->truncated; }
uint64_t McapReader::completeBytes() const { return impl_->complete; }

void McapReader::forEach(const std::function<bool(const MessageView&)>& fn) const {
  const Channel* ch = nullptr;
  for (const Entry& e : impl_->messages) {
    if (!ch || ch->id != e.channel) {
      const auto it = impl_->channels.find(e.channel);
      ch = it == impl_->channels.end() ? nullptr : &it->second;
    }
    const MessageView v{e.channel, ch ? std::string_view(ch->topic) : std::string_view(), e.sequence, e.log, e.publish,
                        e.data};
    if (!fn(v)) return;
  }
}

const google::protobuf::Descriptor* McapReader::descriptor(uint16_t channel_id) const {
  const Decoder* d = impl_->decoder(channel_id);
  return d ? d->type : nullptr;
}

std::unique_ptr<google::protobuf::Message> McapReader::decode(const MessageView& message) const {
  const Decoder* d = impl_->decoder(message.channel_id);
  const std::string what = "mcap: " + impl_->path + ": channel " + std::to_string(message.channel_id);
  if (!d) throw std::runtime_error(what + " is not a protobuf channel with a protobuf schema");
  if (!d->type) throw std::runtime_error(what + ": " + d->error);
  std::unique_ptr<pb::Message> m(d->factory->GetPrototype(d->type)->New());
  if (!m->ParseFromArray(message.data.data(), static_cast<int>(message.data.size())))
    throw std::runtime_error(what + ": message " + std::to_string(message.sequence) + " does not parse as " +
                             d->type->full_name());
  return m;
}

}  // namespace inspect::record
