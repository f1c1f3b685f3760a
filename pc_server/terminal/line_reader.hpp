#pragma once
// Reads lines (or raw key bytes) from a descriptor with a timeout, waking at
// once when the server is asked to stop - std::getline cannot be interrupted.
#include <cstddef>
#include <string>

#include "pc_server/operator/stop_flag.hpp"

namespace inspect::server {

class LineReader {
 public:
  enum class Result { kData, kEof, kStopped, kTimeout, kTooLong };

  /// `max_line` > 0 bounds a line (bytes before its newline): a longer one is
  /// dropped through its newline and reported once as kTooLong, so a peer
  /// cannot make the buffer grow without end. 0 = no limit.
  LineReader(int fd, const StopFlag& stop, std::size_t max_line = 0) : fd_(fd), stop_(stop), max_line_(max_line) {}

  /// Next line without its newline; waits up to `timeout_ms` (< 0: until data, EOF or stop).
  /// A last line without a newline is returned before kEof.
  Result nextLine(std::string& line, int timeout_ms);
  /// Whatever bytes are available (raw terminal keys); same waiting rules.
  Result readChunk(std::string& bytes, int timeout_ms);

 private:
  /// Waits for input; kData when readable.
  Result waitReadable(int timeout_ms);

  int fd_;
  const StopFlag& stop_;
  std::size_t max_line_;
  std::string buf_;
  bool eof_ = false;
  bool skipping_ = false;  // dropping the rest of a line longer than max_line_
};

}  // namespace inspect::server
