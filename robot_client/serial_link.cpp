#include "robot_client/serial_link.hpp"

#include <termios.h>

#include <chrono>
#include <cstring>

#include <boost/asio/write.hpp>

#include "shared/serial/cobs.hpp"
#include "shared/serial/crc16.hpp"
#include "shared/util/clock.hpp"
#include "shared/util/log.hpp"

namespace inspect::client {

namespace asio = boost::asio;

SerialLink::SerialLink(asio::io_context& io, std::string device, int baud, double reopen_period_s)
    : io_(io), port_(io), reopen_timer_(io), device_(std::move(device)), baud_(baud),
      reopen_period_s_(reopen_period_s) {}

SerialLink::~SerialLink() {
  const auto& c = decoder_.counters();
  log::info("serial", device_, ": received ", c.bytes_rx, " bytes, ", c.frames_ok, " frames ok, bad_cobs ", c.bad_cobs,
            ", bad_crc ", c.bad_crc, ", bad_length ", c.bad_length, ", unknown_id ", c.unknown_id, ", overflow ",
            c.overflow, ", seq_gaps ", c.seq_gaps, "; sent ", frames_tx_, " frames (", bytes_tx_, " bytes), ",
            frames_dropped_, " dropped");
}

void SerialLink::start(MessageHandler on_message, StateHandler on_state) {
  log_frames_ = log::level() <= log::Level::kDebug;
  on_message_ = std::move(on_message);
  on_state_ = std::move(on_state);
  tryOpen();
}

void SerialLink::stop() {
  stopped_ = true;
  reopen_timer_.cancel();
  boost::system::error_code ec;
  port_.close(ec);
}

void SerialLink::tryOpen() {
  if (stopped_) return;
  boost::system::error_code ec;
  port_.open(device_, ec);
  if (!ec) {
    using sp = asio::serial_port_base;
    port_.set_option(sp::baud_rate(static_cast<unsigned>(baud_)), ec);
    if (!ec) port_.set_option(sp::character_size(8), ec);
    if (!ec) port_.set_option(sp::parity(sp::parity::none), ec);
    if (!ec) port_.set_option(sp::stop_bits(sp::stop_bits::one), ec);
    if (!ec) port_.set_option(sp::flow_control(sp::flow_control::none), ec);
  }
  if (ec) {
    const std::string why = "cannot open " + device_ + ": " + ec.message();
    if (why != last_error_) log::warn("serial", why, " (retrying every ", reopen_period_s_, " s)");
    last_error_ = why;
    if (port_.is_open()) port_.close(ec);
    scheduleReopen();
    return;
  }
  // Drop whatever the line buffered while nobody was reading.
  ::tcflush(port_.native_handle(), TCIOFLUSH);
  last_error_.clear();
  tx_active_len_ = tx_pending_len_ = 0;
  writing_ = false;
  log::info("serial", "opened ", device_, " at ", baud_, " 8N1");
  on_state_(true, "");
  doRead();
}

void SerialLink::scheduleReopen() {
  reopen_timer_.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(reopen_period_s_)));
  reopen_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) tryOpen();
  });
}

void SerialLink::fail(const std::string& why) {
  if (!port_.is_open()) return;
  log::warn("serial", device_, ": ", why);
  boost::system::error_code ec;
  port_.close(ec);
  on_state_(false, why);
  scheduleReopen();
}

void SerialLink::doRead() {
  port_.async_read_some(asio::buffer(rx_buf_), [this](const boost::system::error_code& ec, std::size_t n) {
    last_read_ns_ = monoNowNs();
    if (ec) {
      if (ec != asio::error::operation_aborted && !stopped_) fail("read failed: " + ec.message());
      return;
    }
    if (log_frames_) {
      decoder_.feed({rx_buf_.data(), n}, [this](const serial::Message& m, uint8_t seq) {
        logFrame(m, seq);
        on_message_(m, seq);
      });
    } else {
      decoder_.feed({rx_buf_.data(), n}, on_message_);
    }
    doRead();
  });
}

void SerialLink::logFrame(const serial::Message& m, uint8_t seq) {
  // The decoded fields encode back to the very bytes that passed the CRC
  // check, so re-encoding gives the frame's wire CRC (to compare with what
  // the sender logged: mcu_sim --frame-log).
  serial::FrameEncoder enc;
  const auto f = enc.encode(m);
  std::array<uint8_t, serial::kMaxRawFrame> raw{};
  const auto n = serial::cobsDecode({f.bytes.data(), f.size - 1}, raw);
  if (!n || *n < 4) return;
  raw[1] = seq;
  const unsigned crc = serial::crc16CcittFalse({raw.data(), *n - 2});
  const auto* sf = std::get_if<serial::SensorFrame>(&m);
  log::debug("serial", "rx frame id=", static_cast<unsigned>(raw[0]), " seq=", static_cast<unsigned>(seq), " crc=", crc,
             " mcu_time_ms=", sf ? sf->mcu_time_ms : 0u);
}

uint8_t SerialLink::send(const serial::Message& msg) {
  const auto f = encoder_.encode(msg);
  if (!port_.is_open()) return f.seq;
  if (tx_pending_len_ + f.size > tx_pending_.size()) {
    ++frames_dropped_;  // the line is not draining; never block the control loop
    return f.seq;
  }
  std::memcpy(tx_pending_.data() + tx_pending_len_, f.bytes.data(), f.size);
  tx_pending_len_ += f.size;
  ++frames_tx_;
  if (!writing_) doWrite();
  return f.seq;
}

void SerialLink::doWrite() {
  if (tx_pending_len_ == 0 || !port_.is_open()) {
    writing_ = false;
    return;
  }
  std::swap(tx_active_, tx_pending_);
  tx_active_len_ = tx_pending_len_;
  tx_pending_len_ = 0;
  writing_ = true;
  asio::async_write(port_, asio::buffer(tx_active_.data(), tx_active_len_),
                    [this](const boost::system::error_code& ec, std::size_t n) {
                      bytes_tx_ += n;
                      if (ec) {
                        writing_ = false;
                        if (ec != asio::error::operation_aborted && !stopped_) fail("write failed: " + ec.message());
                        return;
                      }
                      doWrite();
                    });
}

}  // namespace inspect::client
