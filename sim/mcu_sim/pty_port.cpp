#include "sim/mcu_sim/pty_port.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <system_error>
#include <vector>

namespace inspect::sim {
namespace {

[[noreturn]] void fail(const std::string& what) { throw std::system_error(errno, std::generic_category(), what); }

void makeRaw(int fd, const char* what) {
  termios t{};
  if (tcgetattr(fd, &t) != 0) fail(std::string("tcgetattr ") + what);
  cfmakeraw(&t);
  cfsetispeed(&t, B115200);
  cfsetospeed(&t, B115200);
  if (tcsetattr(fd, TCSANOW, &t) != 0) fail(std::string("tcsetattr ") + what);
}

}  // namespace

PtyPort::PtyPort(const std::string& link_path) {
  master_fd_ = posix_openpt(O_RDWR | O_NOCTTY);
  if (master_fd_ < 0) fail("posix_openpt");
  try {
    if (grantpt(master_fd_) != 0) fail("grantpt");
    if (unlockpt(master_fd_) != 0) fail("unlockpt");
    const char* name = ptsname(master_fd_);
    if (!name) fail("ptsname");
    slave_path_ = name;
    slave_fd_ = ::open(slave_path_.c_str(), O_RDWR | O_NOCTTY);
    if (slave_fd_ < 0) fail("open " + slave_path_);
    // The line discipline is shared by the pair; set it raw on both ends so
    // nothing is echoed or translated before any client has opened the port.
    makeRaw(slave_fd_, slave_path_.c_str());
    makeRaw(master_fd_, "pty master");
    const int fl = fcntl(master_fd_, F_GETFL);
    if (fl < 0 || fcntl(master_fd_, F_SETFL, fl | O_NONBLOCK) != 0) fail("fcntl O_NONBLOCK");
    if (!link_path.empty()) {
      struct stat st{};
      if (lstat(link_path.c_str(), &st) == 0) {
        if (!S_ISLNK(st.st_mode)) {
          errno = EEXIST;
          fail("--pty-link " + link_path + ": exists and is not a symlink; not replacing it");
        }
        if (unlink(link_path.c_str()) != 0) fail("--pty-link " + link_path + ": cannot remove the old symlink");
      }
      if (symlink(slave_path_.c_str(), link_path.c_str()) != 0) fail("--pty-link " + link_path + ": symlink");
      link_path_ = link_path;
    }
  } catch (...) {
    if (slave_fd_ >= 0) ::close(slave_fd_);
    ::close(master_fd_);
    throw;
  }
}

PtyPort::PtyPort(const Device& device) : slave_path_(device.path) {
  master_fd_ = ::open(device.path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  if (master_fd_ < 0) fail("--hil " + device.path);
  try {
    makeRaw(master_fd_, device.path.c_str());
  } catch (...) {
    ::close(master_fd_);
    throw;
  }
}

PtyPort::~PtyPort() {
  if (!link_path_.empty()) {
    // Remove the link only if it is still ours (another mcu_sim may have replaced it).
    std::vector<char> buf(4096);
    const ssize_t n = readlink(link_path_.c_str(), buf.data(), buf.size() - 1);
    if (n > 0 && std::string(buf.data(), static_cast<std::size_t>(n)) == slave_path_) unlink(link_path_.c_str());
  }
  if (slave_fd_ >= 0) ::close(slave_fd_);
  if (master_fd_ >= 0) ::close(master_fd_);
}

std::size_t PtyPort::write(std::span<const uint8_t> bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(master_fd_, bytes.data() + done, bytes.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    break;  // EAGAIN (buffer full: nobody reading) or an error: drop the rest
  }
  bytes_written_ += done;
  bytes_dropped_ += bytes.size() - done;
  return done;
}

std::size_t PtyPort::read(std::span<uint8_t> out) {
  for (;;) {
    const ssize_t n = ::read(master_fd_, out.data(), out.size());
    if (n > 0) {
      bytes_read_ += static_cast<std::size_t>(n);
      return static_cast<std::size_t>(n);
    }
    if (n < 0 && errno == EINTR) continue;
    return 0;  // EAGAIN: nothing waiting (EIO cannot happen while we hold the slave open)
  }
}

}  // namespace inspect::sim
