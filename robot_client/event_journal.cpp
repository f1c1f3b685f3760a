#include "robot_client/event_journal.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <stdexcept>

#include <boost/crc.hpp>

#include "shared/util/file_util.hpp"

namespace inspect::client {

namespace {

constexpr std::size_t kHeader = 20;                // magic 2, type 1, pad 1, length 4, seq 8, crc 4
constexpr uint32_t kMaxPayload = 1u << 20;          // an Envelope on the link is at most 1 MiB too

void putLe(std::string& s, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) s.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

uint64_t getLe(const unsigned char* p, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= static_cast<uint64_t>(p[i]) << (8 * i);
  return v;
}

uint32_t crcOf(char type, uint32_t length, uint64_t seq, const char* payload, std::size_t n) {
  std::string head;
  head.push_back(type);
  putLe(head, length, 4);
  putLe(head, seq, 8);
  boost::crc_32_type crc;  // CRC-32 (IEEE 802.3, zlib's): Boost.CRC, header-only
  crc.process_bytes(head.data(), head.size());
  crc.process_bytes(payload, n);
  return crc.checksum();
}

std::string encode(char type, uint64_t seq, const std::string& payload) {
  std::string r;
  r.reserve(kHeader + payload.size());
  r += "IJ";
  r.push_back(type);
  r.push_back('\0');
  putLe(r, payload.size(), 4);
  putLe(r, seq, 8);
  putLe(r, crcOf(type, static_cast<uint32_t>(payload.size()), seq, payload.data(), payload.size()), 4);
  r += payload;
  return r;
}

// A whole, valid record at `p` (of `end - p` bytes): its size, else 0.
std::size_t validAt(const unsigned char* p, std::size_t left) {
  if (left < kHeader || p[0] != 'I' || p[1] != 'J') return 0;
  const char type = static_cast<char>(p[2]);
  if (type != 'H' && type != 'E' && type != 'D' && type != 'X') return 0;
  const auto length = static_cast<uint32_t>(getLe(p + 4, 4));
  if (length > kMaxPayload || left < kHeader + length) return 0;
  const uint64_t seq = getLe(p + 8, 8);
  const auto crc = static_cast<uint32_t>(getLe(p + 16, 4));
  if (crc != crcOf(type, length, seq, reinterpret_cast<const char*>(p + kHeader), length)) return 0;
  return kHeader + length;
}

std::string why(const unsigned char* p, std::size_t left) {
  if (left < kHeader) return "torn record at the end (" + std::to_string(left) + " bytes, power lost mid-write?)";
  if (p[0] != 'I' || p[1] != 'J') return "no record starts here (bad magic)";
  const auto length = static_cast<uint32_t>(getLe(p + 4, 4));
  if (length > kMaxPayload) return "record length " + std::to_string(length) + " is above 1 MiB";
  if (left < kHeader + length)
    return "torn record at the end (" + std::to_string(left) + " of " + std::to_string(kHeader + length) + " bytes)";
  return "checksum mismatch (seq " + std::to_string(getLe(p + 8, 8)) + ")";
}

}  // namespace

uint64_t EventJournal::newStreamId() {
  std::random_device rd;
  uint64_t v = 0;
  while (v == 0) v = (static_cast<uint64_t>(rd()) << 32) ^ rd();
  return v;
}

EventJournal::Loaded EventJournal::read(const std::string& path) {
  Loaded out;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    out.created = true;
    return out;
  }
  const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto* base = reinterpret_cast<const unsigned char*>(data.data());
  std::size_t pos = 0;
  uint64_t delivered = 0, max_seq = 0;
  bool header = false;
  std::vector<Entry> entries;
  std::vector<uint64_t> dropped;
  while (pos < data.size()) {
    const std::size_t n = validAt(base + pos, data.size() - pos);
    if (n == 0) {
      // Skip to the next valid record (or the end), saying why once.
      const std::string reason = why(base + pos, data.size() - pos);
      std::size_t next = pos + 1;
      while (next < data.size() && validAt(base + next, data.size() - next) == 0) ++next;
      out.skipped.push_back("offset " + std::to_string(pos) + ": " + reason + "; " + std::to_string(next - pos) +
                            " bytes skipped");
      pos = next;
      continue;
    }
    const char type = static_cast<char>(base[pos + 2]);
    const uint64_t seq = getLe(base + pos + 8, 8);
    const std::string payload = data.substr(pos + kHeader, n - kHeader);
    if (type == 'H' && payload.size() >= 16) {
      out.stream = getLe(reinterpret_cast<const unsigned char*>(payload.data()), 8);
      const uint64_t next = getLe(reinterpret_cast<const unsigned char*>(payload.data()) + 8, 8);
      if (next > 0) max_seq = std::max(max_seq, next - 1);
      header = true;
    } else if (type == 'E') {
      entries.push_back({seq, payload});
      max_seq = std::max(max_seq, seq);
    } else if (type == 'D') {
      delivered = std::max(delivered, seq);
      max_seq = std::max(max_seq, seq);
    } else if (type == 'X') {
      dropped.push_back(seq);
    }
    pos += n;
  }
  if (!header || out.stream == 0) {
    // Without its header the entries' stream is unknown: the server could
    // take them for another sequence's. Start a new stream; keep the entries
    // (they are resent under it, numbered anew by the caller's next_seq).
    out.created = true;
    out.stream = 0;
  }
  for (auto& e : entries)
    if (e.seq > delivered && std::find(dropped.begin(), dropped.end(), e.seq) == dropped.end())
      out.pending.push_back(std::move(e));
  out.next_seq = max_seq + 1;
  return out;
}

EventJournal::EventJournal(const std::string& path, double sync_period_s)
    : path_(path), sync_period_s_(sync_period_s) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path parent = fs::path(path).parent_path();
  if (!parent.empty()) fs::create_directories(parent, ec);
  loaded_ = read(path);
  if (loaded_.stream == 0) {
    loaded_.stream = newStreamId();
    // Entries read without a header get numbers of the new stream.
    for (auto& e : loaded_.pending) e.seq = loaded_.next_seq++;
  }
  stream_ = loaded_.stream;
  if (!rewrite(loaded_.pending, loaded_.next_seq)) {
    // Could not write the compacted file: append to what is there.
    fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0640);
    if (fd_ < 0) throw std::runtime_error("journal " + path + ": cannot open: " + std::strerror(errno));
  }
  sync_thread_ = std::thread([this] { syncLoop(); });
}

EventJournal::~EventJournal() {
  {
    std::lock_guard lk(mu_);
    stopping_ = true;
  }
  cv_.notify_all();
  if (sync_thread_.joinable()) sync_thread_.join();
  if (fd_ >= 0) {
    ::fdatasync(fd_);
    ::close(fd_);
  }
}

bool EventJournal::rewrite(const std::vector<Entry>& pending, uint64_t next_seq) {
  std::string data;
  std::string head;
  putLe(head, stream_, 8);
  putLe(head, next_seq, 8);
  data += encode('H', 0, head);
  for (const auto& e : pending) data += encode('E', e.seq, e.payload);
  if (const std::string why = writeFileAtomically(path_, data, /*durable=*/true); !why.empty()) {
    std::lock_guard lk(mu_);
    error_ = why;
    ++write_errors_;
    return false;
  }
  const int nfd = ::open(path_.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (nfd < 0) {
    std::lock_guard lk(mu_);
    error_ = "cannot reopen " + path_ + ": " + std::strerror(errno);
    ++write_errors_;
    return false;
  }
  std::lock_guard lk(mu_);
  if (fd_ >= 0) ::close(fd_);
  fd_ = nfd;
  bytes_ = data.size();
  dirty_ = false;
  error_.clear();
  return true;
}

bool EventJournal::compact(const std::vector<Entry>& pending, uint64_t next_seq) {
  return rewrite(pending, next_seq);
}

bool EventJournal::writeRecord(char type, uint64_t seq, const std::string& payload) {
  const std::string rec = encode(type, seq, payload);
  std::unique_lock lk(mu_);
  if (fd_ < 0) {
    error_ = "journal not open";
    ++write_errors_;
    return false;
  }
  // One write() per record: a SIGKILL never leaves half of one in the file
  // (the page cache keeps what write() took); a short write (disk full) is
  // cut back off, so the next record starts clean.
  ssize_t n;
  do n = ::write(fd_, rec.data(), rec.size());
  while (n < 0 && errno == EINTR);
  if (n != static_cast<ssize_t>(rec.size())) {
    const int err = n < 0 ? errno : ENOSPC;
    if (n > 0 && ::ftruncate(fd_, static_cast<off_t>(bytes_)) != 0) bytes_ += static_cast<uint64_t>(n);
    error_ = std::string("cannot append to ") + path_ + ": " + std::strerror(err) + " (kept in memory)";
    ++write_errors_;
    return false;
  }
  bytes_ += rec.size();
  error_.clear();
  dirty_ = true;
  lk.unlock();
  if (sync_period_s_ <= 0) {
    std::lock_guard g(mu_);
    ::fdatasync(fd_);
    dirty_ = false;
  } else {
    cv_.notify_all();
  }
  return true;
}

bool EventJournal::append(uint64_t seq, const std::string& payload) { return writeRecord('E', seq, payload); }

bool EventJournal::markDelivered(uint64_t up_to_seq) { return writeRecord('D', up_to_seq, {}); }

bool EventJournal::markDropped(uint64_t seq) { return writeRecord('X', seq, {}); }

std::string EventJournal::error() const {
  std::lock_guard lk(mu_);
  return error_;
}

void EventJournal::syncLoop() {
  std::unique_lock lk(mu_);
  while (!stopping_) {
    cv_.wait(lk, [this] { return stopping_ || dirty_; });
    if (stopping_) break;
    // At most one sync per period: a power cut loses at most that much.
    cv_.wait_for(lk, std::chrono::duration<double>(sync_period_s_), [this] { return stopping_; });
    // A duplicate: the syncing thread never holds the lock through the sync
    // (the loop's appends go on), and a compaction may close fd_ meanwhile.
    const int fd = fd_ >= 0 ? ::fcntl(fd_, F_DUPFD_CLOEXEC, 0) : -1;
    dirty_ = false;
    lk.unlock();
    if (fd >= 0) {
      ::fdatasync(fd);
      ::close(fd);
    }
    lk.lock();
  }
}

}  // namespace inspect::client
