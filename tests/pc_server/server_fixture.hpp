#pragma once
// A LinkServer on 127.0.0.1, ephemeral port, as pc_server runs it: the
// acceptor on an io_context run by 2 threads, the sessions on 2 session threads.
#include <gtest/gtest.h>

#include <memory>
#include <optional>
#include <thread>
#include <vector>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>

#include "pc_server/link/link_server.hpp"
#include "pc_server/link/robot_registry.hpp"
#include "pc_server/link/session_threads.hpp"
#include "shared/util/clock.hpp"
#include "tests/support/fake_robot/scripted_robot.hpp"

namespace inspect::test {

inline server::ServerConfig testConfig() {
  server::ServerConfig c;
  c.bind_address = "127.0.0.1";
  c.port = 0;
  c.server_id = "test_server";
  c.telemetry_stale_s = 0;  // test robots often send no telemetry; LinkServerTest.StaleTelemetry* turns it on
  const std::string certs = testCertsDir();
  c.tls.ca = certs + "/ca.pem";
  c.tls.cert = certs + "/server.pem";
  c.tls.key = certs + "/server.key";
  return c;
}

class ServerFixture : public ::testing::Test {
 protected:
  void startServer(server::ServerConfig config = testConfig()) {
    link_ = std::make_unique<server::LinkServer>(ioc_, config, registry_, &sessions_);
    port_ = link_->listen().port();
    work_.emplace(ioc_.get_executor());
    sessions_.start();
    for (int i = 0; i < 2; ++i) threads_.emplace_back([this] { ioc_.run(); });
  }

  void TearDown() override {
    if (link_) {
      link_->stop();
      link_->waitAllClosed(std::chrono::seconds(1));
    }
    sessions_.stop();
    work_.reset();
    ioc_.stop();
    for (auto& t : threads_) t.join();
  }

  /// Polls `pred` every 10 ms for up to `timeout`.
  template <class Pred>
  static bool eventually(Pred pred, std::chrono::milliseconds timeout = std::chrono::milliseconds(2000)) {
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline) {
      if (pred()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return pred();
  }

  std::optional<server::RobotSnapshot> snap(const std::string& id) { return registry_.snapshot(id, monoNowNs()); }
  bool connected(const std::string& id) {
    const auto s = snap(id);
    return s && s->connected;
  }

  server::SessionThreads sessions_{2};  // outlives ioc_: a pending accept holds a socket of its io_contexts
  boost::asio::io_context ioc_;
  server::RobotRegistry registry_;
  std::unique_ptr<server::LinkServer> link_;
  std::optional<boost::asio::executor_work_guard<boost::asio::io_context::executor_type>> work_;
  std::vector<std::thread> threads_;
  uint16_t port_ = 0;
};

}  // namespace inspect::test
