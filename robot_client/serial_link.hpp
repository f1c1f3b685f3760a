#pragma once
// The MCU serial line: Boost.Asio serial_port (8N1, no flow control), frame
// decoding, and a non-blocking write path. Reopens the device when it fails.
#include <array>
#include <functional>
#include <string>

#include <boost/asio/io_context.hpp>
#include <boost/asio/serial_port.hpp>
#include <boost/asio/steady_timer.hpp>

#include "shared/serial/frame_codec.hpp"

namespace inspect::client {

class SerialLink {
 public:
  using MessageHandler = std::function<void(const serial::Message&, uint8_t seq)>;
  using StateHandler = std::function<void(bool open, const std::string& why)>;

  SerialLink(boost::asio::io_context& io, std::string device, int baud, double reopen_period_s);
  /// Logs the line's counters (frames in and out, errors by kind).
  ~SerialLink();
  SerialLink(const SerialLink&) = delete;
  SerialLink& operator=(const SerialLink&) = delete;

  /// Starts opening the device (and keeps retrying while it fails).
  void start(MessageHandler on_message, StateHandler on_state);
  void stop();

  /// Queues a message; never blocks. Returns the frame's sequence number.
  uint8_t send(const serial::Message& msg);

  bool isOpen() const { return port_.is_open(); }
  const serial::DecoderCounters& rxCounters() const { return decoder_.counters(); }
  uint64_t bytesTx() const { return bytes_tx_; }
  uint64_t framesTx() const { return frames_tx_; }
  uint64_t framesDropped() const { return frames_dropped_; }
  /// When the bytes being decoded were read (monoNowNs): a handler of a
  /// message knows how long ago its frame came in.
  int64_t lastReadNs() const { return last_read_ns_; }

 private:
  void tryOpen();
  void scheduleReopen();
  void doRead();
  void doWrite();
  void fail(const std::string& why);
  /// Debug log of an accepted frame: id, sequence number, wire CRC (and MCU time of a sensor frame).
  void logFrame(const serial::Message& m, uint8_t seq);

  boost::asio::io_context& io_;
  boost::asio::serial_port port_;
  boost::asio::steady_timer reopen_timer_;
  std::string device_;
  int baud_;
  double reopen_period_s_;
  MessageHandler on_message_;
  StateHandler on_state_;
  bool stopped_ = false;
  int64_t last_read_ns_ = 0;
  bool log_frames_ = false;  // INSPECT_LOG=debug: one line per accepted frame
  std::string last_error_;

  serial::FrameEncoder encoder_;
  serial::FrameDecoder decoder_;
  std::array<uint8_t, 512> rx_buf_{};
  // Double buffer: one being written by the OS, one collecting new frames.
  std::array<uint8_t, 2048> tx_active_{};
  std::size_t tx_active_len_ = 0;
  std::array<uint8_t, 2048> tx_pending_{};
  std::size_t tx_pending_len_ = 0;
  bool writing_ = false;
  uint64_t bytes_tx_ = 0;
  uint64_t frames_tx_ = 0;
  uint64_t frames_dropped_ = 0;
};

}  // namespace inspect::client
