#include "tests/support/udp_relay.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace inspect::test {
sockaddr_in loopbackAddress(uint16_t port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  return a;
}

UdpRelay::UdpRelay(uint16_t target_port, const UdpRelayParams& p) : target_(target_port), p_(p) {
  in_ = ::socket(AF_INET, SOCK_DGRAM, 0);
  out_ = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (in_ < 0 || out_ < 0) throw std::runtime_error("udp_relay: socket failed");
  int rcv = 4 << 20;
  ::setsockopt(in_, SOL_SOCKET, SO_RCVBUF, &rcv, sizeof rcv);
  sockaddr_in a = loopbackAddress(0);
  if (::bind(in_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) throw std::runtime_error("udp_relay: bind failed");
  socklen_t len = sizeof a;
  ::getsockname(in_, reinterpret_cast<sockaddr*>(&a), &len);
  port_ = ntohs(a.sin_port);
  thread_ = std::thread([this] { run(); });
}

UdpRelay::~UdpRelay() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  if (in_ >= 0) ::close(in_);
  if (out_ >= 0) ::close(out_);
}

void UdpRelay::run() {
  std::mt19937_64 rng(p_.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const sockaddr_in to = loopbackAddress(target_);
  auto send = [&](const std::vector<uint8_t>& d) {
    ::sendto(out_, d.data(), d.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
    ++c_.sent;
  };
  std::vector<uint8_t> buf(65536), held;
  bool holding = false;
  uint64_t index = 0;
  while (!stop_) {
    pollfd pfd{in_, POLLIN, 0};
    if (::poll(&pfd, 1, 20) <= 0) {
      if (holding) {  // nothing came after the held one: let it go
        send(held);
        holding = false;
      }
      continue;
    }
    const ssize_t n = ::recv(in_, buf.data(), buf.size(), 0);
    if (n < 0) continue;
    ++c_.received;
    const uint64_t i = index++;
    std::vector<uint8_t> d(buf.begin(), buf.begin() + n);
    const bool in_burst = p_.burst_len > 0 && i >= p_.burst_from && i < p_.burst_from + p_.burst_len;
    if (in_burst || u(rng) < p_.drop) {
      ++c_.dropped;
      continue;
    }
    if (p_.delay_ms > 0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(p_.delay_ms));
    if (!holding && u(rng) < p_.reorder) {
      held = std::move(d);
      holding = true;
      ++c_.reordered;
      continue;
    }
    send(d);
    if (u(rng) < p_.duplicate) {
      send(d);
      ++c_.duplicated;
    }
    if (holding) {
      send(held);
      holding = false;
    }
  }
}

}  // namespace inspect::test
