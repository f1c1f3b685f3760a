#pragma once
// A text file written by a thread of its own, so that the simulated MCU's
// real-time loop never waits on the disk: a write() into ext4 can block for
// half a second while the journal commits under a concurrent build (measured:
// docs/simulator.md), and a real MCU never stalls for its logger. The loop
// appends to a memory buffer; the writer thread writes it out every
// `period_ms` (readers of a live file see lines at most that late).
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>

namespace inspect::sim {

class BackgroundFile {
 public:
  /// Opens (truncates) `path`; throws std::runtime_error naming `what`, the path and the reason.
  BackgroundFile(const std::string& path, std::string_view what, int period_ms = 20);
  /// Writes out what is buffered, then closes.
  ~BackgroundFile();
  BackgroundFile(const BackgroundFile&) = delete;
  BackgroundFile& operator=(const BackgroundFile&) = delete;

  /// Appends `text` (never blocks on the disk). Past kMaxBuffered bytes not yet
  /// written (a disk stalled for minutes), text is dropped and counted.
  void append(std::string_view text);
  /// Blocks until everything appended so far is written and flushed.
  void sync();
  /// Bytes dropped because the buffer was full.
  uint64_t droppedBytes() const;
  /// The longest single write-out seen so far, ms (what the loop would have waited).
  double maxWriteMs() const;

  static constexpr std::size_t kMaxBuffered = 64u << 20;

 private:
  void run();
  std::FILE* file_ = nullptr;
  const int period_ms_;
  mutable std::mutex mu_;
  std::condition_variable cv_;       // wakes the writer (stop, sync)
  std::condition_variable written_;  // wakes sync()
  std::string pending_;
  uint64_t appended_ = 0;  // total bytes appended (incl. dropped)
  uint64_t written_upto_ = 0;
  uint64_t dropped_ = 0;
  double max_write_ms_ = 0.0;
  bool stop_ = false;
  bool sync_wanted_ = false;
  std::thread thread_;
};

}  // namespace inspect::sim
