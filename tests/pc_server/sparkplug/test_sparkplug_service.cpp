// The edge node's MQTT session against brokers that do not answer
// (pc_server/sparkplug/sparkplug_service, mqtt_session): real sockets on
// 127.0.0.1, no broker. A host that drops the SYN, a listener that accepts
// and says nothing, and a closed port: each is named in the service's
// error, and none holds stop().
#include <gtest/gtest.h>

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <thread>

#include "pc_server/link/robot_registry.hpp"
#include "pc_server/sparkplug/sparkplug_service.hpp"

using namespace inspect;
using namespace inspect::server;
using namespace inspect::server::sparkplug;
using Clock = std::chrono::steady_clock;

namespace {

/// A TCP socket on 127.0.0.1, an ephemeral port; closed at the end.
struct Socket {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  ~Socket() {
    if (fd >= 0) ::close(fd);
  }
  uint16_t listen(int backlog) {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(fd, backlog) != 0) return 0;
    socklen_t len = sizeof a;
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
    return ntohs(a.sin_port);
  }
  bool connect(uint16_t port) {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(port);
    return ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  }
};

SparkplugConfig brokerAt(uint16_t port) {
  SparkplugConfig c;
  c.enabled = true;
  c.host = "127.0.0.1";
  c.port = port;
  c.keepalive_s = 5;  // the CONNACK is given up after this (libmosquitto's least)
  return c;
}

/// Polls the service's error for up to `timeout` (every 20 ms) until it contains `what`.
std::string errorContaining(const SparkplugService& s, const std::string& what, std::chrono::milliseconds timeout) {
  const auto until = Clock::now() + timeout;
  std::string e;
  while (Clock::now() < until) {
    e = s.stats().error;
    if (e.find(what) != std::string::npos) return e;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return e;
}

double stopSeconds(SparkplugService& s) {
  const auto t0 = Clock::now();
  s.stop();
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// The service's error against a broker at `port` once it contains `what`
/// (waited for up to `timeout`); its stop() must then return within 2 s.
std::string errorOfABrokerAt(uint16_t port, const std::string& what, std::chrono::milliseconds timeout) {
  RobotRegistry registry;
  SparkplugService s(brokerAt(port), "pc1", registry);
  s.start();
  const std::string e = errorContaining(s, what, timeout);
  EXPECT_LT(stopSeconds(s), 2.0) << "stop() waited";
  return e;
}

}  // namespace

TEST(SparkplugService, ABrokerHostThatDropsTheSynDoesNotHoldStop) {
  // A listen queue of one, already taken: Linux drops the next SYN, as a
  // firewall or a dead host on the plant network would. A blocking connect
  // held the edge node's thread, and stop(), for the kernel's connect
  // timeout (about 2 minutes); the CONNACK wait is the next test's.
  Socket listener;
  const uint16_t port = listener.listen(0);
  ASSERT_NE(port, 0);
  Socket first;
  ASSERT_TRUE(first.connect(port));
  RobotRegistry registry;
  SparkplugService s(brokerAt(port), "pc1", registry);
  s.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // the SYN sent, and dropped
  EXPECT_FALSE(s.stats().connected);
  EXPECT_EQ(s.stats().sessions, 0u);
  EXPECT_EQ(s.stats().error, "") << "nothing has failed yet: the connect is pending";
  const double took = stopSeconds(s);
  EXPECT_LT(took, 2.0) << "stop() waited for the connect";
}

TEST(SparkplugService, ABrokerThatAcceptsAndSaysNothingIsGivenUpAfterTheKeepAlive) {
  Socket listener;
  const uint16_t port = listener.listen(8);  // the kernel completes the handshake; nobody reads
  ASSERT_NE(port, 0);
  EXPECT_EQ(errorOfABrokerAt(port, "no answer (CONNACK)", std::chrono::milliseconds(8000)),
            "no answer (CONNACK) from 127.0.0.1:" + std::to_string(port) + " within 5 s (keepalive_s)");
}

TEST(SparkplugService, AClosedPortIsNamedWithTheSystemsReason) {
  uint16_t port = 0;
  {
    Socket probe;  // a port that was free a moment ago: nothing listens there now
    port = probe.listen(1);
  }
  ASSERT_NE(port, 0);
  EXPECT_EQ(errorOfABrokerAt(port, "cannot connect", std::chrono::milliseconds(3000)),
            "cannot connect to 127.0.0.1:" + std::to_string(port) + ": Connection refused");
}
