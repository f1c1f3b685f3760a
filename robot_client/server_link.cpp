#include "robot_client/server_link.hpp"

#include <chrono>

#include <boost/asio/connect.hpp>
#include <boost/asio/write.hpp>

#include "shared/net/link_version.hpp"
#include "shared/util/clock.hpp"
#include "shared/util/log.hpp"

namespace inspect::client {

namespace asio = boost::asio;
using asio::ip::tcp;

namespace {
constexpr std::size_t kMaxQueued = 256;
}  // namespace

ServerLink::ServerLink(asio::io_context& io, const ClientConfig& cfg)
    : io_(io),
      cfg_(cfg),
      resolver_(io),
      tls_(cfg.tls.plaintext ? nullptr
                             : net::makeTlsContext({cfg.tls.ca, cfg.tls.cert, cfg.tls.key}, net::TlsRole::kClient)),
      retry_timer_(io),
      handshake_timer_(io),
      heartbeat_timer_(io),
      backoff_s_(cfg.reconnect_min_s) {
  if (tls_) log::info("link", "mutual TLS, robot certificate ", net::describeCertificate(cfg.tls.cert));
}

void ServerLink::start(Handlers h) {
  h_ = std::move(h);
  connect();
}

void ServerLink::stop() {
  stopped_ = true;
  retry_timer_.cancel();
  handshake_timer_.cancel();
  heartbeat_timer_.cancel();
  if (stream_) stream_->close();
}

void ServerLink::connect() {
  if (stopped_) return;
  const uint64_t gen = ++generation_;
  resolver_.async_resolve(
      cfg_.server_host, std::to_string(cfg_.server_port),
      [this, gen](const boost::system::error_code& ec, tcp::resolver::results_type results) {
        if (gen != generation_ || stopped_) return;
        if (ec) {
          close("cannot resolve " + cfg_.server_host + ": " + ec.message());
          return;
        }
        stream_ = std::make_shared<net::LinkStream>(tcp::socket(io_), tls_);
        if (tls_) stream_->expectServerName(cfg_.tls.server_name);
        asio::async_connect(stream_->socket(), results,
                            [this, gen, s = stream_](const boost::system::error_code& ec2, const tcp::endpoint&) {
                              if (gen != generation_ || stopped_) return;
                              if (ec2) {
                                close("cannot connect to " + cfg_.server_host + ":" +
                                      std::to_string(cfg_.server_port) + ": " + ec2.message());
                                return;
                              }
                              onTcpConnected();
                            });
      });
}

void ServerLink::onTcpConnected() {
  boost::system::error_code ec;
  stream_->socket().set_option(tcp::no_delay(true), ec);
  const uint64_t gen = generation_;
  // One deadline for the TLS handshake and the HelloReply.
  handshake_timer_.expires_after(steadyDuration(cfg_.handshake_timeout_s));
  handshake_timer_.async_wait([this, gen](const boost::system::error_code& e) {
    if (!e && gen == generation_ && !up_)
      close("no handshake reply within " + std::to_string(cfg_.handshake_timeout_s) + " s");
  });
  stream_->asyncHandshake(asio::ssl::stream_base::client, [this, gen, s = stream_](const boost::system::error_code& e) {
    if (gen != generation_ || stopped_) return;
    if (e) {
      close("TLS handshake with " + cfg_.server_host + ":" + std::to_string(cfg_.server_port) +
            " failed: " + net::describeHandshakeError(e, s->ssl()));
      return;
    }
    onConnected();
  });
}

void ServerLink::onConnected() {
  connected_ = true;
  decoder_ = net::DelimitedDecoder();
  tx_queue_.clear();
  v1::Envelope hello;
  auto* h = hello.mutable_hello();
  h->set_robot_id(cfg_.robot_id);
  h->set_protocol_version(net::kProtocolVersion);
  h->add_capabilities("teleop");
  h->add_capabilities("video");
  h->add_capabilities("ptz");
  if (!hello_.gas_channels.empty()) h->add_capabilities("gas");
  for (const auto& g : hello_.gas_channels) *h->add_gas_channels() = g;
  h->set_gas_inlet_x_m(hello_.inlet_x_m);
  h->set_gas_inlet_y_m(hello_.inlet_y_m);
  h->set_software_version(INSPECT_VERSION);
  if (hello_.filler) hello_.filler(*h);
  send(hello);
  doRead();
}

void ServerLink::scheduleReconnect() {
  if (stopped_) return;
  retry_timer_.expires_after(steadyDuration(backoff_s_));
  backoff_s_ = std::clamp(backoff_s_ * 2.0, cfg_.reconnect_min_s, cfg_.reconnect_max_s);
  retry_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) connect();
  });
}

void ServerLink::close(const std::string& why) {
  ++generation_;
  const bool was_up = up_;
  up_ = false;
  connected_ = false;
  handshake_timer_.cancel();
  heartbeat_timer_.cancel();
  if (stream_) stream_->close();
  tx_queue_.clear();
  if (was_up || why != last_error_) log::warn("link", why);
  last_error_ = why;
  if (was_up && h_.on_down) h_.on_down(why);
  // A link that was up is retried at once (a server restart, a blip), then
  // with backoff from reconnect_min_s up to reconnect_max_s.
  if (was_up) backoff_s_ = 0.0;
  scheduleReconnect();
}

void ServerLink::doRead() {
  const uint64_t gen = generation_;
  stream_->asyncReadSome(asio::buffer(rx_buf_), [this, gen, s = stream_](const boost::system::error_code& ec,
                                                                          std::size_t n) {
    if (gen != generation_ || stopped_) return;
    if (ec) {
      if (ec == asio::error::eof || ec == asio::ssl::error::stream_truncated)
        close(std::string("server closed the connection") +
              (!up_ && !tls_ ? " before the handshake reply (does it expect TLS? this robot runs --plaintext)" : ""));
      else
        close("read failed: " + ec.message());
      return;
    }
    last_rx_ns_ = monoNowNs();
    decoder_.append(rx_buf_.data(), n);
    std::span<const uint8_t> frame;
    for (;;) {
      const auto st = decoder_.next(frame);
      if (st == net::DelimitedDecoder::Status::kNeedMore) break;
      if (st == net::DelimitedDecoder::Status::kInvalid) {
        close("bad frame from server: " + decoder_.error());
        return;
      }
      v1::Envelope env;
      if (!net::DelimitedDecoder::parse(frame, env)) {
        close("malformed message from server (" + std::to_string(frame.size()) + " bytes)");
        return;
      }
      if (!up_) {
        if (env.body_case() != v1::Envelope::kHelloReply) {
          close("server sent a message before the handshake reply");
          return;
        }
        const auto& r = env.hello_reply();
        if (!r.accepted()) {
          close("server rejected the handshake: " + r.reason());
          return;
        }
        up_ = true;
        last_rx_ns_ = monoNowNs();
        ++counts_.connects;
        backoff_s_ = cfg_.reconnect_min_s;
        handshake_timer_.cancel();
        last_error_.clear();
        log::info("link", "connected to ", cfg_.server_host, ":", cfg_.server_port, " as ", cfg_.robot_id,
                  " (server ", r.server_id(), ")");
        if (h_.on_up) h_.on_up();
        heartbeat();
        continue;
      }
      if (h_.on_message) h_.on_message(env);
      if (gen != generation_) return;  // the handler closed the link
    }
    doRead();
  });
}

void ServerLink::heartbeat() {
  if (!up_) return;
  // Half-open link: the server heartbeats every 50 ms, so 0.8 s of silence (checked at every
  // heartbeat of ours, 0.1 s) means it is gone: closed within 0.9 s (docs/failsafes.md).
  if (monoNowNs() - last_rx_ns_ > static_cast<int64_t>(kDeadAfterS * 1e9)) {
    close("no data from the server for " + std::to_string(kDeadAfterS) + " s (half-open link)");
    return;
  }
  v1::Envelope env;
  env.mutable_heartbeat()->set_time_us(monoNowUs());
  send(env);
  const uint64_t gen = generation_;
  heartbeat_timer_.expires_after(steadyDuration(cfg_.server_heartbeat_period_s));
  heartbeat_timer_.async_wait([this, gen](const boost::system::error_code& ec) {
    if (!ec && gen == generation_) heartbeat();
  });
}

void ServerLink::send(v1::Envelope& env) {
  if (!connected_) return;
  if (tx_queue_.size() >= kMaxQueued) {
    ++counts_.dropped;
    return;
  }
  env.set_seq(next_seq_++);
  env.set_send_time_us(monoNowUs());
  std::string bytes;
  net::appendDelimited(env, bytes);
  const bool idle = tx_queue_.empty();
  tx_queue_.push_back(std::move(bytes));
  if (idle) doWrite();
}

void ServerLink::doWrite() {
  const uint64_t gen = generation_;
  stream_->asyncWrite(asio::buffer(tx_queue_.front()), [this, gen, s = stream_](const boost::system::error_code& ec,
                                                                               std::size_t) {
    if (gen != generation_ || stopped_) return;
    if (ec) {
      close("write failed: " + ec.message());
      return;
    }
    tx_queue_.pop_front();
    if (!tx_queue_.empty()) doWrite();
  });
}

}  // namespace inspect::client
