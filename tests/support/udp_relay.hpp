#pragma once
// Test-only UDP relay on loopback: receives datagrams on 127.0.0.1:<port>
// and forwards them to 127.0.0.1:<target>, dropping, duplicating, reordering
// and delaying them at given rates (seeded, reproducible). What the target
// sends back (to the relay's forwarding socket: RTCP feedback) goes back to
// the last sender, dropped at the same rate and delayed as much, from a
// random stream of its own (the forward direction's losses do not change
// with the feedback). Delays are a queue, not a sleep: a delayed datagram
// does not hold up the ones after it. Runs on its own thread; every wait is
// bounded.
#include <netinet/in.h>

#include <atomic>
#include <cstdint>
#include <thread>

namespace inspect::test {

/// 127.0.0.1:port as a socket address.
sockaddr_in loopbackAddress(uint16_t port);

struct UdpRelayParams {
  double drop = 0.0;        // probability a datagram is lost
  double duplicate = 0.0;   // probability it is sent twice
  double reorder = 0.0;     // probability it is held back and sent after the next one
  double delay_ms = 0.0;    // fixed extra one-way delay (both directions)
  uint32_t seed = 1;
  // A burst: every datagram with index in [burst_from, burst_from + burst_len) is lost.
  uint64_t burst_from = 0;
  uint64_t burst_len = 0;
  bool drop_back = true;    // feedback is lost at `drop` too (index bursts are forward only)
  // Periodic bursts (both ways, with drop_back): for burst_ms of every
  // burst_every_ms (from the relay's start) a datagram is lost with
  // probability burst_drop instead of drop.
  double burst_every_ms = 0, burst_ms = 0, burst_drop = 0;
};

struct UdpRelayCounters {
  std::atomic<uint64_t> received{0}, sent{0}, dropped{0}, duplicated{0}, reordered{0};
  std::atomic<uint64_t> bytes_sent{0};  // forwarded to the target (duplicates included)
  std::atomic<uint64_t> back_received{0}, back_sent{0}, back_dropped{0};  // target -> sender
};

class UdpRelay {
 public:
  /// Binds 127.0.0.1:0 and starts forwarding to 127.0.0.1:target_port. Throws std::runtime_error.
  UdpRelay(uint16_t target_port, const UdpRelayParams& p);
  ~UdpRelay();
  UdpRelay(const UdpRelay&) = delete;
  UdpRelay& operator=(const UdpRelay&) = delete;

  uint16_t port() const { return port_; }
  const UdpRelayCounters& counters() const { return c_; }

 private:
  void run();
  int in_ = -1, out_ = -1;
  uint16_t port_ = 0, target_ = 0;
  UdpRelayParams p_;
  UdpRelayCounters c_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace inspect::test
