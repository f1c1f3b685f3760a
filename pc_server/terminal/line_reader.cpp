#include "pc_server/terminal/line_reader.hpp"

#include <poll.h>
#include <unistd.h>

#include <cerrno>

namespace inspect::server {

LineReader::Result LineReader::waitReadable(int timeout_ms) {
  if (stop_.requested()) return Result::kStopped;
  pollfd fds[2] = {{fd_, POLLIN, 0}, {stop_.wakeFd(), POLLIN, 0}};
  const int n = ::poll(fds, stop_.wakeFd() >= 0 ? 2 : 1, timeout_ms);
  if (stop_.requested()) return Result::kStopped;
  if (n < 0) return errno == EINTR ? Result::kTimeout : Result::kEof;
  if (n == 0) return Result::kTimeout;
  if (fds[0].revents & (POLLIN | POLLHUP | POLLERR | POLLNVAL)) return Result::kData;
  return Result::kTimeout;
}

LineReader::Result LineReader::readChunk(std::string& bytes, int timeout_ms) {
  bytes.clear();
  if (!buf_.empty()) {
    bytes.swap(buf_);
    return Result::kData;
  }
  if (eof_) return Result::kEof;
  const Result r = waitReadable(timeout_ms);
  if (r != Result::kData) return r;
  char tmp[4096];
  const auto n = ::read(fd_, tmp, sizeof tmp);
  if (n < 0 && (errno == EINTR || errno == EAGAIN)) return Result::kTimeout;
  if (n <= 0) {
    eof_ = true;
    return Result::kEof;
  }
  bytes.assign(tmp, static_cast<std::size_t>(n));
  return Result::kData;
}

LineReader::Result LineReader::nextLine(std::string& line, int timeout_ms) {
  for (;;) {
    const auto nl = buf_.find('\n');
    if (skipping_) {
      if (nl == std::string::npos) {
        buf_.clear();
      } else {
        buf_.erase(0, nl + 1);
        skipping_ = false;
        continue;
      }
    } else if (nl != std::string::npos) {
      if (max_line_ > 0 && nl > max_line_) {
        buf_.erase(0, nl + 1);
        return Result::kTooLong;
      }
      line = buf_.substr(0, nl);
      buf_.erase(0, nl + 1);
      return Result::kData;
    } else if (max_line_ > 0 && buf_.size() > max_line_) {
      buf_.clear();
      skipping_ = true;
      return Result::kTooLong;
    }
    if (eof_) {
      if (buf_.empty()) return Result::kEof;
      line.swap(buf_);
      buf_.clear();
      return Result::kData;
    }
    const Result r = waitReadable(timeout_ms);
    if (r != Result::kData) return r;
    char tmp[4096];
    const auto n = ::read(fd_, tmp, sizeof tmp);
    if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
    if (n <= 0) eof_ = true;
    else buf_.append(tmp, static_cast<std::size_t>(n));
  }
}

}  // namespace inspect::server
