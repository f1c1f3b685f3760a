#include "tests/support/udp_relay.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
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
  using Clock = std::chrono::steady_clock;
  std::mt19937_64 rng(p_.seed), back_rng(p_.seed ^ 0x9E3779B97F4A7C15ULL);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const sockaddr_in to = loopbackAddress(target_);
  sockaddr_in from{};  // the last sender: where feedback goes
  bool have_from = false;
  const auto delay = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double, std::milli>(p_.delay_ms));
  struct Due {
    Clock::time_point at;
    bool back;
    std::vector<uint8_t> d;
  };
  const auto started = Clock::now();
  // The loss probability now: drop, or burst_drop inside a periodic burst.
  auto lossNow = [&] {
    if (p_.burst_every_ms <= 0 || p_.burst_ms <= 0) return p_.drop;
    const double t_ms = std::chrono::duration<double, std::milli>(Clock::now() - started).count();
    return std::fmod(t_ms, p_.burst_every_ms) < p_.burst_ms ? p_.burst_drop : p_.drop;
  };
  std::deque<Due> queue;  // in release order (the delay is the same for every datagram)
  auto emit = [&](bool back, const std::vector<uint8_t>& d) {
    if (back) {
      ::sendto(in_, d.data(), d.size(), 0, reinterpret_cast<const sockaddr*>(&from), sizeof from);
      ++c_.back_sent;
    } else {
      ::sendto(out_, d.data(), d.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
      ++c_.sent;
      c_.bytes_sent += d.size();
    }
  };
  auto send = [&](bool back, std::vector<uint8_t> d) {
    if (delay.count() > 0)
      queue.push_back({Clock::now() + delay, back, std::move(d)});
    else
      emit(back, d);
  };
  // out_ must have a local port before the target can answer it.
  {
    sockaddr_in a = loopbackAddress(0);
    ::bind(out_, reinterpret_cast<sockaddr*>(&a), sizeof a);
  }
  std::vector<uint8_t> buf(65536), held;
  bool holding = false;
  uint64_t index = 0;
  while (!stop_) {
    while (!queue.empty() && queue.front().at <= Clock::now()) {
      emit(queue.front().back, queue.front().d);
      queue.pop_front();
    }
    int wait_ms = 20;
    if (!queue.empty())
      wait_ms = static_cast<int>(std::clamp<int64_t>(
          std::chrono::duration_cast<std::chrono::milliseconds>(queue.front().at - Clock::now()).count(), 0, 20));
    pollfd pfd[2] = {{in_, POLLIN, 0}, {out_, POLLIN, 0}};
    if (::poll(pfd, 2, wait_ms) <= 0) {
      if (holding && queue.empty()) {  // nothing came after the held one: let it go
        send(false, std::move(held));
        holding = false;
      }
      continue;
    }
    if (pfd[1].revents & POLLIN) {  // feedback from the target
      const ssize_t n = ::recv(out_, buf.data(), buf.size(), 0);
      if (n >= 0) {
        ++c_.back_received;
        if (!have_from || (p_.drop_back && u(back_rng) < lossNow()))
          ++c_.back_dropped;
        else
          send(true, std::vector<uint8_t>(buf.begin(), buf.begin() + n));
      }
    }
    if (!(pfd[0].revents & POLLIN)) continue;
    sockaddr_in src{};
    socklen_t slen = sizeof src;
    const ssize_t n = ::recvfrom(in_, buf.data(), buf.size(), 0, reinterpret_cast<sockaddr*>(&src), &slen);
    if (n < 0) continue;
    from = src;
    have_from = true;
    ++c_.received;
    const uint64_t i = index++;
    std::vector<uint8_t> d(buf.begin(), buf.begin() + n);
    const bool in_burst = p_.burst_len > 0 && i >= p_.burst_from && i < p_.burst_from + p_.burst_len;
    if (in_burst || u(rng) < lossNow()) {
      ++c_.dropped;
      continue;
    }
    if (!holding && u(rng) < p_.reorder) {
      held = std::move(d);
      holding = true;
      ++c_.reordered;
      continue;
    }
    const bool dup = u(rng) < p_.duplicate;
    if (dup) {
      send(false, d);
      ++c_.duplicated;
    }
    send(false, std::move(d));
    if (holding) {
      send(false, std::move(held));
      holding = false;
    }
  }
}

}  // namespace inspect::test
