#pragma once
// The robot's event journal: a small append-only file on the robot's storage
// that keeps the events (and late acks) the server has not yet confirmed,
// across a lost link, a SIGKILL or a power cut (docs/store-and-forward.md).
//
// Records, little-endian, each checked by a CRC-32:
//
//   magic "IJ" (2) | type (1) | 0 (1) | length (u32) | seq (u64) | crc32 (u32) | payload (length bytes)
//
// the CRC (CRC-32 of IEEE 802.3, Boost.CRC) covering type, length, seq and payload. Types: 'H' (the file's
// header: payload = event stream id u64 + next sequence number u64), 'E' (an
// entry: payload = the serialized Envelope), 'D' (delivered: the server
// confirmed every entry up to seq), 'X' (dropped: entry seq left the full
// queue). Every record is written with one write()
// (the kernel keeps it through a SIGKILL); a sync thread calls fdatasync at
// most once a second, so a power cut loses at most the last second. Reading
// back skips a torn or corrupt record (bad magic, length, CRC; a torn tail)
// with a logged reason and resynchronises on the next valid record; then the
// file is rewritten with only what is still pending (writeFileAtomically,
// durable: temporary file, fsync, rename, fsync of the folder), so a damaged
// file never grows. A write that fails (disk full, I/O
// error) is reported (error()) and retried with the next record: the entries
// stay in memory, nothing stops.
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace inspect::client {

class EventJournal {
 public:
  struct Entry {
    uint64_t seq = 0;
    std::string payload;  // a serialized v1::Envelope
  };
  /// What opening found in the file.
  struct Loaded {
    uint64_t stream = 0;            // the event stream id (new: random, never 0)
    uint64_t next_seq = 1;          // the sequence number the next entry gets
    std::vector<Entry> pending;     // entries not yet delivered, in order
    std::vector<std::string> skipped;  // one line per record skipped, with why
    bool created = false;           // no journal was there (or none was readable)
  };

  /// Opens the journal at `path` (creating it and its folder), reads it back
  /// and compacts it. `sync_period_s` <= 0 syncs after every record (tests).
  /// Throws std::runtime_error only when the file cannot be opened or
  /// created at all; the caller then runs without a journal.
  EventJournal(const std::string& path, double sync_period_s = 1.0);
  ~EventJournal();
  EventJournal(const EventJournal&) = delete;
  EventJournal& operator=(const EventJournal&) = delete;

  /// What the file held when opened (moved out by the caller once).
  Loaded& loaded() { return loaded_; }

  /// Appends an entry / a delivered mark. False when the write failed (error() says why).
  bool append(uint64_t seq, const std::string& payload);
  bool markDelivered(uint64_t up_to_seq);
  bool markDropped(uint64_t seq);
  /// Rewrites the file with `pending` only (when everything was delivered, or
  /// it grew past its bound). False on failure (the old file stays).
  bool compact(const std::vector<Entry>& pending, uint64_t next_seq);

  /// Bytes in the file now.
  uint64_t bytes() const { return bytes_; }
  /// The last write error ("" = none since the last good write).
  std::string error() const;
  uint64_t writeErrors() const { return write_errors_; }
  const std::string& path() const { return path_; }

  /// Reads a journal file (no side effects): for tests and `open`.
  static Loaded read(const std::string& path);
  /// A random event stream id, never 0.
  static uint64_t newStreamId();

 private:
  bool writeRecord(char type, uint64_t seq, const std::string& payload);
  bool rewrite(const std::vector<Entry>& pending, uint64_t next_seq);
  void syncLoop();

  std::string path_;
  double sync_period_s_;
  int fd_ = -1;
  uint64_t bytes_ = 0;
  uint64_t stream_ = 0;
  uint64_t write_errors_ = 0;
  Loaded loaded_;
  mutable std::mutex mu_;  // fd_ against the sync thread; error_
  std::condition_variable cv_;
  bool dirty_ = false;
  bool stopping_ = false;
  std::string error_;
  std::thread sync_thread_;
};

}  // namespace inspect::client
