#pragma once
// TCP link to pc_server: connect with backoff, handshake, delimited protobuf
// envelopes both ways, heartbeats, a bounded write queue.
#include <array>
#include <deque>
#include <functional>
#include <memory>
#include <string>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>

#include "inspect_robot/v1/link.pb.h"
#include "robot_client/client_config.hpp"
#include "shared/net/delimited_codec.hpp"
#include "shared/net/tls.hpp"

namespace inspect::client {

class ServerLink {
 public:
  struct Handlers {
    std::function<void()> on_up;                              // handshake accepted
    std::function<void(const std::string& why)> on_down;      // link lost (after being up)
    std::function<void(const v1::Envelope&)> on_message;      // any message after the handshake
  };

  /// Loads the TLS files of cfg.tls unless cfg.tls.plaintext; throws net::TlsError naming the file.
  ServerLink(boost::asio::io_context& io, const ClientConfig& cfg);

  void start(Handlers h);
  /// Gas channels announced in every Hello (set before start()).
  void setGasChannels(std::vector<v1::GasChannelInfo> channels, double inlet_x_m, double inlet_y_m) {
    hello_.gas_channels = std::move(channels);
    hello_.inlet_x_m = inlet_x_m;
    hello_.inlet_y_m = inlet_y_m;
  }
  /// Called to complete every Hello just before it is sent.
  void setHelloFiller(std::function<void(v1::Hello&)> f) { hello_.filler = std::move(f); }
  void stop();

  /// Queues an envelope (seq and send time are filled in). Dropped when the
  /// link is down or the queue is full (telemetry must never block the loop).
  void send(v1::Envelope& env);

  bool isUp() const { return up_; }
  /// Envelopes waiting in the send queue.
  std::size_t queued() const { return tx_queue_.size(); }
  uint64_t connects() const { return counts_.connects; }
  uint64_t dropped() const { return counts_.dropped; }

 private:
  void connect();
  void onTcpConnected();
  void onConnected();
  void scheduleReconnect();
  void doRead();
  void doWrite();
  void close(const std::string& why);
  void heartbeat();

  boost::asio::io_context& io_;
  ClientConfig cfg_;
  struct HelloParts {  // what every Hello carries besides the id and the version
    std::vector<v1::GasChannelInfo> gas_channels;
    double inlet_x_m = 0.0, inlet_y_m = 0.0;
    std::function<void(v1::Hello&)> filler;
  } hello_;
  Handlers h_;
  boost::asio::ip::tcp::resolver resolver_;
  std::shared_ptr<boost::asio::ssl::context> tls_;  // null: --plaintext
  std::shared_ptr<net::LinkStream> stream_;         // a new one per connection; handlers keep theirs alive
  boost::asio::steady_timer retry_timer_;
  boost::asio::steady_timer handshake_timer_;
  boost::asio::steady_timer heartbeat_timer_;
  net::DelimitedDecoder decoder_;
  std::array<char, 16384> rx_buf_{};
  std::deque<std::string> tx_queue_;
  bool connected_ = false;  // TCP up
  bool up_ = false;         // handshake accepted
  bool stopped_ = false;
  double backoff_s_;
  uint64_t next_seq_ = 1;
  struct Counts {
    uint64_t connects = 0;
    uint64_t dropped = 0;  // envelopes not queued because the send queue was full (none are counted while the link is down)
  } counts_;
  uint64_t generation_ = 0;
  int64_t last_rx_ns_ = 0;
  static constexpr double kDeadAfterS = 0.8;  // invalidates handlers of an old connection
  std::string last_error_;
};

}  // namespace inspect::client
