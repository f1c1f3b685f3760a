#include "pc_server/link/link_server.hpp"

#include <boost/asio/post.hpp>
#include <boost/asio/strand.hpp>

#include "pc_server/link/robot_session.hpp"
#include "pc_server/link/session_threads.hpp"
#include "shared/util/startup_error.hpp"
#include "shared/util/clock.hpp"
#include "shared/util/log.hpp"

namespace inspect::server {

namespace asio = boost::asio;
using asio::ip::tcp;
using boost::system::error_code;

LinkServer::LinkServer(asio::io_context& ioc, const LinkConfig& config, RobotRegistry& registry,
                       SessionThreads* sessions)
    : ioc_(ioc),
      session_threads_(sessions),
      config_(config),
      registry_(registry),
      acceptor_(asio::make_strand(ioc)),
      accept_retry_timer_(acceptor_.get_executor()) {}

LinkServer::~LinkServer() = default;

tcp::endpoint LinkServer::listen() {
  if (!config_.tls.plaintext) {
    try {
      tls_ = net::makeTlsContext({config_.tls.ca, config_.tls.cert, config_.tls.key}, net::TlsRole::kServer);
      cert_info_ = net::describeCertificate(config_.tls.cert);
    } catch (const net::TlsError& e) {
      throw util::StartupError(std::string("TLS: ") + e.what() + " (or --plaintext for an isolated test bench)");
    }
  }
  error_code ec;
  const auto address = asio::ip::make_address(config_.bind_address, ec);
  if (ec) throw util::StartupError("bind address '" + config_.bind_address + "' is not an IP address");
  const tcp::endpoint want(address, config_.port);
  const std::string where = config_.bind_address + ":" + std::to_string(config_.port);
  acceptor_.open(want.protocol(), ec);
  if (!ec) acceptor_.set_option(tcp::acceptor::reuse_address(true), ec);
  if (!ec) acceptor_.bind(want, ec);
  if (!ec) acceptor_.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) throw util::StartupError("cannot listen on " + where + ": " + ec.message());
  const auto got = acceptor_.local_endpoint(ec);
  if (ec) throw util::StartupError("cannot read the listening address: " + ec.message());
  asio::post(acceptor_.get_executor(), [this] { doAccept(); });
  return got;
}

void LinkServer::doAccept() {
  auto strand = asio::make_strand(session_threads_ ? session_threads_->next() : ioc_);
  acceptor_.async_accept(strand, [this, strand](const error_code& ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted || !acceptor_.is_open()) return;
    if (ec) {
      // E.g. out of file descriptors: retry shortly instead of spinning.
      log::warn(log::tag::kLink, "accept failed: ", ec.message());
      accept_retry_timer_.expires_after(std::chrono::milliseconds(100));
      accept_retry_timer_.async_wait([this](const error_code& e) {
        if (!e) doAccept();
      });
      return;
    }
    auto session = std::make_shared<RobotSession>(strand, std::move(socket), tls_, *this, registry_, config_,
                                                  next_serial_.fetch_add(1));
    {
      std::lock_guard lk(mu_);
      if (stopped_) return;  // the socket closes with the dropped session
      live_.insert(session);
    }
    log::debug(log::tag::kLink, "connection from ", session->address());
    session->start();
    doAccept();
  });
}

void LinkServer::stop() {
  std::vector<std::shared_ptr<RobotSession>> sessions;
  {
    std::lock_guard lk(mu_);
    if (stopped_) return;
    stopped_ = true;
    sessions.assign(live_.begin(), live_.end());
  }
  asio::post(acceptor_.get_executor(), [this] {
    error_code ignored;
    acceptor_.close(ignored);
    accept_retry_timer_.cancel();
  });
  for (const auto& s : sessions) s->close("server shutting down");
}

bool LinkServer::waitAllClosed(std::chrono::steady_clock::duration timeout) {
  std::unique_lock lk(mu_);
  return all_closed_cv_.wait_for(lk, timeout, [this] { return live_.empty(); });
}

std::size_t LinkServer::sessionCount() const {
  std::lock_guard lk(mu_);
  return live_.size();
}

void LinkServer::attach(const std::string& robot_id, const std::shared_ptr<RobotSession>& session) {
  std::shared_ptr<RobotSession> old;
  bool stopped = false;
  {
    std::lock_guard lk(mu_);
    stopped = stopped_;
    if (!stopped) {
      auto& slot = by_robot_[robot_id];
      old = slot;
      slot = session;
    }
  }
  if (stopped) session->close("server shutting down");
  if (old && old != session) old->close("replaced by a new connection from " + session->address());
}

void LinkServer::detach(const std::shared_ptr<RobotSession>& session, const std::string& robot_id) {
  {
    std::lock_guard lk(mu_);
    live_.erase(session);
    if (const auto it = by_robot_.find(robot_id); it != by_robot_.end() && it->second == session)
      by_robot_.erase(it);
  }
  all_closed_cv_.notify_all();
}

std::shared_ptr<RobotSession> LinkServer::find(const std::string& robot_id) const {
  std::lock_guard lk(mu_);
  const auto it = by_robot_.find(robot_id);
  return it == by_robot_.end() ? nullptr : it->second;
}

void LinkServer::consoleAlive() { console_alive_ns_ = monoNowNs(); }

void LinkServer::setConsoleWatchdog(std::chrono::milliseconds timeout) {
  console_alive_ns_ = monoNowNs();
  console_watchdog_ns_ = std::chrono::duration_cast<std::chrono::nanoseconds>(timeout).count();
}

bool LinkServer::consoleResponsive() const {
  const int64_t wd = console_watchdog_ns_;
  return wd <= 0 || monoNowNs() - console_alive_ns_ <= wd;
}

uint64_t LinkServer::setTeleop(const std::string& robot_id, double v_m_s, double w_rad_s, double lease_s) {
  const auto s = find(robot_id);
  if (!s) return 0;
  const uint64_t id = nextCommandId();
  s->setTeleop(v_m_s, w_rad_s, id, lease_s);
  return id;
}

void LinkServer::renewTeleop(const std::string& robot_id, double lease_s) {
  if (const auto s = find(robot_id)) s->renewTeleop(lease_s);
}

void LinkServer::clearTeleop(const std::string& robot_id) {
  if (const auto s = find(robot_id)) s->clearTeleop();
}

uint64_t LinkServer::sendCommand(const std::string& robot_id, v1::Command cmd) {
  const auto s = find(robot_id);
  if (!s) return 0;
  const uint64_t id = nextCommandId();
  cmd.set_id(id);
  s->sendCommand(std::move(cmd));
  return id;
}

}  // namespace inspect::server
