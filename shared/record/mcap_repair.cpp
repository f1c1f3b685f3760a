// Crash repair of a run.mcap (docs/mcap.md): the data section scanned up to
// its last complete chunk, the summary written again after it.
#include "shared/record/mcap_writer.hpp"

#include "shared/record/mcap_records.hpp"

namespace inspect::record {
using namespace detail;
using namespace mcap;

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
