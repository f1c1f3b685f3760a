#pragma once
// The emulated MCU's serial port: the master side of a pseudo-terminal in raw,
// non-blocking mode. The slave side is what robot_client opens.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace inspect::sim {

/// A pty pair owned by mcu_sim (or a terminal device it opened). Throws std::system_error when it cannot be set up.
class PtyPort {
 public:
  /// Opens the pty; when link_path is non-empty, points a symlink there at the
  /// slave device (replacing an existing symlink, never another kind of file).
  explicit PtyPort(const std::string& link_path = "");
  /// An existing terminal device instead (mcu_sim --hil: the pty QEMU made for
  /// the firmware board's USART2), raw and non-blocking; nothing is linked.
  struct Device {
    std::string path;
  };
  explicit PtyPort(const Device& device);
  ~PtyPort();
  PtyPort(const PtyPort&) = delete;
  PtyPort& operator=(const PtyPort&) = delete;

  /// Master fd, for poll().
  int fd() const { return master_fd_; }
  /// The slave device, e.g. /dev/pts/7.
  const std::string& slavePath() const { return slave_path_; }
  const std::string& linkPath() const { return link_path_; }

  /// Writes what the pty accepts now; the rest is dropped and counted (nobody reading).
  std::size_t write(std::span<const uint8_t> bytes);
  /// Reads what the host has written; 0 when nothing is waiting.
  std::size_t read(std::span<uint8_t> out);

  uint64_t bytesWritten() const { return bytes_written_; }
  uint64_t bytesDropped() const { return bytes_dropped_; }
  uint64_t bytesRead() const { return bytes_read_; }

 private:
  int master_fd_ = -1;
  int slave_fd_ = -1;  // held open so the master never sees a hang-up when the client closes
  std::string slave_path_;
  std::string link_path_;
  uint64_t bytes_written_ = 0;
  uint64_t bytes_dropped_ = 0;
  uint64_t bytes_read_ = 0;
};

}  // namespace inspect::sim
