#pragma once
// The firmware's QEMU board as robot_client sees it, for the tests and the
// benchmark: scripts/mcu_qemu.sh started with the image (and, with --world,
// mcu_sim --hil), its USART1 opened raw as a serial line; frames read with
// their arrival time, messages sent through the Pi's own codec.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "shared/serial/frame_codec.hpp"
#include "tests/support/process.hpp"

namespace inspect::test {

class QemuBoard {
 public:
  struct Frame {
    int64_t host_ns;  // arrival, test::nowNs()
    serial::SensorFrame frame;
  };

  /// Starts scripts/mcu_qemu.sh --serial-link <dir>/usart1 --elf <elf> <extra...>
  /// (its output in <dir>/qemu.out and qemu.err) and opens the line. Throws
  /// std::runtime_error with QEMU's messages when it does not come up in 20 s.
  QemuBoard(const std::string& elf, const std::string& dir, const std::vector<std::string>& extra = {});
  ~QemuBoard();
  QemuBoard(const QemuBoard&) = delete;
  QemuBoard& operator=(const QemuBoard&) = delete;

  /// Reads the line for `seconds`, appending every sensor frame to frames().
  void pump(double seconds);
  void send(const serial::Message& m);
  void write(std::span<const uint8_t> bytes);
  /// robot_client's rhythm for `seconds`: wheel commands every 20 ms, a heartbeat every 100 ms.
  void drive(double seconds, int16_t left_mrad_s, int16_t right_mrad_s);
  /// The sequence number the next wheel command gets.
  uint8_t nextWheelSeq() const { return next_wheel_seq_; }
  /// When the last wheel command was written (test::nowNs()).
  int64_t lastWheelNs() const { return last_wheel_ns_; }

  std::vector<Frame>& frames() { return frames_; }
  const serial::DecoderCounters& counters() const { return decoder_.counters(); }
  serial::FrameEncoder& encoder() { return encoder_; }
  /// SIGTERM to the script (it stops QEMU and mcu_sim) and waits; its stdout.
  std::string stop(double timeout_s = 10.0);
  /// Waits for the script to end by itself (mcu_sim's --duration); its stdout, or "" on timeout.
  std::string waitForEnd(double timeout_s);
  std::string errors() const;

 private:
  std::string dir_;
  Process script_;
  int fd_ = -1;
  serial::FrameDecoder decoder_;
  serial::FrameEncoder encoder_;
  uint8_t next_wheel_seq_ = 0;
  int64_t last_wheel_ns_ = 0;
  std::vector<Frame> frames_;
};

}  // namespace inspect::test
