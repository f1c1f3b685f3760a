#pragma once
// A minimal robot for the link tests: a blocking POSIX socket, the shared
// delimited framing and an optional background pump (heartbeats, telemetry,
// automatic Acks). Every wait is bounded in time.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "inspect/v1/link.pb.h"
#include "shared/net/delimited_codec.hpp"
#include "shared/net/link_version.hpp"

namespace inspect::test {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

class TestRobot {
 public:
  struct Received {
    Clock::time_point t;
    v1::Envelope env;
  };

  TestRobot() = default;
  ~TestRobot() {
    stopPump();
    close();
  }
  TestRobot(const TestRobot&) = delete;
  TestRobot& operator=(const TestRobot&) = delete;

  bool connect(uint16_t port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd_ < 0) return false;
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) return false;
    int one = 1;
    ::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    return true;
  }

  /// Half-close: the server reads EOF (no reset), the robot can still read.
  void shutdownWrite() { ::shutdown(fd_, SHUT_WR); }

  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

  bool sendRaw(const std::string& bytes) {
    std::lock_guard lk(tx_mu_);
    std::size_t off = 0;
    while (off < bytes.size()) {
      const auto n = ::send(fd_, bytes.data() + off, bytes.size() - off, MSG_NOSIGNAL);
      if (n <= 0) return false;
      off += static_cast<std::size_t>(n);
    }
    return true;
  }

  bool send(v1::Envelope env) {
    env.set_seq(++tx_seq_);
    std::string wire;
    return net::appendDelimited(env, wire) && sendRaw(wire);
  }

  /// The next message from the server, or nullopt on timeout / close.
  std::optional<v1::Envelope> receive(std::chrono::milliseconds timeout) {
    const auto deadline = Clock::now() + timeout;
    for (;;) {
      std::span<const uint8_t> f;
      const auto st = decoder_.next(f);
      if (st == net::DelimitedDecoder::Status::kFrame) {
        v1::Envelope e;
        if (!net::DelimitedDecoder::parse(f, e)) return std::nullopt;
        return e;
      }
      if (st == net::DelimitedDecoder::Status::kInvalid) return std::nullopt;
      if (!readSome(deadline)) return std::nullopt;
    }
  }

  /// Sends Hello and returns the HelloReply (skipping nothing else: it must come first).
  std::optional<v1::HelloReply> hello(const std::string& id, uint32_t version = net::kProtocolVersion) {
    v1::Envelope e;
    e.mutable_hello()->set_robot_id(id);
    e.mutable_hello()->set_protocol_version(version);
    e.mutable_hello()->add_capabilities("teleop");
    e.mutable_hello()->set_software_version("test");
    if (!send(e)) return std::nullopt;
    const auto r = receive(2000ms);
    if (!r || !r->has_hello_reply()) return std::nullopt;
    return r->hello_reply();
  }

  /// Reads and discards until the server closes the connection; false on timeout.
  bool waitClosed(std::chrono::milliseconds timeout) {
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline) {
      if (!readSome(deadline)) return peer_closed_;
    }
    return peer_closed_;
  }

  /// Background thread: heartbeats every 100 ms, telemetry at `telemetry_hz` (0 = none)
  /// with pose.x = a counter, and an Ack for every Command (see ackPolicy).
  void startPump(double telemetry_hz, bool heartbeats = true) {
    pumping_ = true;
    pump_ = std::thread([this, telemetry_hz, heartbeats] { pumpLoop(telemetry_hz, heartbeats); });
  }
  void stopPump() {
    pumping_ = false;
    if (pump_.joinable()) pump_.join();
  }

  /// Decides the Ack of a Command; default ACCEPTED. Set before startPump.
  std::function<v1::Ack(const v1::Command&)> ack_policy = [](const v1::Command& c) {
    v1::Ack a;
    a.set_command_id(c.id());
    a.set_status(v1::Ack::ACCEPTED);
    return a;
  };
  bool auto_ack = true;

  std::vector<Received> received() const {
    std::lock_guard lk(rx_mu_);
    return rx_;
  }
  int count(v1::Envelope::BodyCase c) const {
    std::lock_guard lk(rx_mu_);
    int n = 0;
    for (const auto& r : rx_) n += r.env.body_case() == c;
    return n;
  }
  bool peerClosed() const { return peer_closed_; }
  uint64_t telemetrySent() const { return telemetry_sent_; }

 private:
  bool readSome(Clock::time_point deadline) {
    if (fd_ < 0 || peer_closed_) return false;
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) return false;
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(left)) <= 0) return false;
    char buf[8192];
    const auto n = ::recv(fd_, buf, sizeof buf, 0);
    if (n <= 0) {
      peer_closed_ = true;
      return false;
    }
    decoder_.append(buf, static_cast<std::size_t>(n));
    return true;
  }

  void pumpLoop(double telemetry_hz, bool heartbeats) {
    auto next_hb = Clock::now();
    auto next_tlm = Clock::now();
    const auto tlm_period = telemetry_hz > 0 ? std::chrono::duration_cast<Clock::duration>(
                                                   std::chrono::duration<double>(1.0 / telemetry_hz))
                                             : Clock::duration::max();
    while (pumping_ && !peer_closed_) {
      const auto now = Clock::now();
      if (heartbeats && now >= next_hb) {
        v1::Envelope e;
        e.mutable_heartbeat()->set_time_us(1);
        send(e);
        next_hb = now + 100ms;
      }
      if (telemetry_hz > 0 && now >= next_tlm) {
        v1::Envelope e;
        auto* t = e.mutable_telemetry();
        t->mutable_pose()->set_x_m(static_cast<double>(++telemetry_sent_));
        t->set_mode(v1::TELEOP);
        t->set_battery_v(24.0);
        send(e);
        next_tlm += tlm_period;
        if (next_tlm < now) next_tlm = now + tlm_period;
      }
      if (auto m = receive(5ms)) {
        {
          std::lock_guard lk(rx_mu_);
          rx_.push_back({Clock::now(), *m});
        }
        if (auto_ack && m->has_command()) {
          v1::Envelope a;
          *a.mutable_ack() = ack_policy(m->command());
          send(a);
        }
      }
    }
  }

  int fd_ = -1;
  net::DelimitedDecoder decoder_;
  std::atomic<bool> peer_closed_{false};
  std::atomic<uint64_t> tx_seq_{0};
  std::atomic<uint64_t> telemetry_sent_{0};
  std::mutex tx_mu_;
  mutable std::mutex rx_mu_;
  std::vector<Received> rx_;
  std::atomic<bool> pumping_{false};
  std::thread pump_;
};

}  // namespace inspect::test
