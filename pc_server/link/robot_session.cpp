#include "pc_server/link/robot_session.hpp"

#include <boost/asio/post.hpp>
#include <boost/asio/write.hpp>

#include "pc_server/link/hello_check.hpp"
#include "pc_server/link/link_server.hpp"
#include "pc_server/link/robot_registry.hpp"
#include "shared/net/link_version.hpp"
#include "shared/util/clock.hpp"
#include "shared/util/number_text.hpp"

namespace inspect::server {

using util::fmtShort;

namespace asio = boost::asio;
using boost::system::error_code;

namespace {

const char* bodyName(v1::Envelope::BodyCase c) {
  switch (c) {
    case v1::Envelope::kHello: return "Hello";
    case v1::Envelope::kHelloReply: return "HelloReply";
    case v1::Envelope::kHeartbeat: return "Heartbeat";
    case v1::Envelope::kCommand: return "Command";
    case v1::Envelope::kAck: return "Ack";
    case v1::Envelope::kTelemetry: return "Telemetry";
    case v1::Envelope::kEvent: return "Event";
    case v1::Envelope::kDelivered: return "Delivered";
    case v1::Envelope::BODY_NOT_SET: break;
  }
  return "an Envelope without a body";
}

std::chrono::nanoseconds seconds(double s) {
  return std::chrono::nanoseconds(static_cast<int64_t>(s * 1e9));
}
}  // namespace

RobotSession::RobotSession(Strand strand, asio::ip::tcp::socket socket,
                           const std::shared_ptr<asio::ssl::context>& tls, LinkServer& server, RobotRegistry& registry,
                           const LinkConfig& config, uint64_t serial)
    : strand_(strand),
      stream_(std::move(socket), tls),
      server_(server),
      registry_(registry),
      config_(config),
      serial_(serial),
      handshake_timer_(strand_),
      watchdog_timer_(strand_),
      heartbeat_timer_(strand_),
      teleop_timer_(strand_),
      stale_timer_(strand_),
      throttle_{{config.robot_limits.messages_per_s, config.robot_limits.messages_per_s * config.robot_limits.burst_s},
                {config.robot_limits.bytes_per_s, config.robot_limits.bytes_per_s * config.robot_limits.burst_s}},
      decoder_(config.max_frame_bytes),
      rx_arena_block_(new char[kRxArenaBlock]) {
  google::protobuf::ArenaOptions arena_options;
  arena_options.initial_block = rx_arena_block_.get();
  arena_options.initial_block_size = kRxArenaBlock;
  rx_arena_ = std::make_unique<google::protobuf::Arena>(arena_options);
  error_code ec;
  const auto ep = stream_.socket().remote_endpoint(ec);
  address_ = ec ? std::string("?") : ep.address().to_string() + ":" + std::to_string(ep.port());
  stream_.socket().set_option(asio::ip::tcp::no_delay(true), ec);  // small frames, latency matters
}

bool RobotSession::withinLimits(std::size_t bytes) {
  const double now_s = static_cast<double>(monoNowNs()) * 1e-9;
  auto& t = throttle_;
  const auto& lim = config_.robot_limits;
  if (t.messages.take(1, now_s) && t.bytes.take(static_cast<double>(bytes), now_s)) {
    if (t.active && now_s - t.last_drop_s >= 1.0) {
      t.active = false;
      const std::string text = "server: no longer throttled, " + std::to_string(t.dropped) + " messages dropped in " +
                               fmtShort(t.last_drop_s - t.since_s, 1) + " s";
      log::info(log::tag::kLink, who(), ": ", text.substr(8));
      serverEvent(v1::Event::FAULT_CLEARED, text);
    }
    return true;
  }
  if (!t.active) {
    t.active = true;
    t.since_s = now_s;
    t.dropped = 0;
    ++t.episodes;
    const std::string text = "server: throttled: over " + fmtShort(lim.messages_per_s, 0) + " messages/s or " +
                             fmtShort(lim.bytes_per_s, 0) + " bytes/s; its messages are dropped until it slows down";
    log::warn(log::tag::kLink, who(), ": ", text.substr(8));
    serverEvent(v1::Event::FAULT_RAISED, text);
  }
  ++t.dropped;
  t.last_drop_s = now_s;
  if (now_s - t.since_s >= lim.close_after_s)
    closeNow("flooding: over the limits (robot_limits) for " + fmtShort(now_s - t.since_s, 1) + " s, " +
                 std::to_string(t.dropped) + " messages dropped",
             log::Level::kWarn);
  return false;
}

void RobotSession::serverEvent(v1::Event::Kind kind, const std::string& text) {
  v1::Envelope env;
  auto* ev = env.mutable_event();
  ev->set_kind(kind);
  ev->set_text(text);
  ev->set_robot_time_us(monoNowUs());
  if (peer_.robot_id.empty()) return;  // before the Hello: the log says it
  registry_.onEvent(peer_.robot_id, serial_, *ev, monoNowNs());
  server_.observe(peer_.robot_id, address_, env, true, monoNowUs());
}

std::string RobotSession::who() const { return peer_.robot_id.empty() ? address_ : peer_.robot_id + " (" + address_ + ")"; }

void RobotSession::start() {
  asio::post(strand_, [self = shared_from_this()] {
    self->live_.last_rx = Clock::now();
    self->handshake_timer_.expires_after(seconds(self->config_.handshake_timeout_s));
    self->handshake_timer_.async_wait([self](const error_code& ec) {
      if (ec || self->closed_ || self->peer_.accepted || self->peer_.rejecting) return;
      self->closeNow(std::string(self->peer_.cert_name.empty() && self->stream_.tls() ? "no TLS handshake" : "no Hello") +
                         " within " + fmtShort(self->config_.handshake_timeout_s) + " s (handshake timeout)",
                     log::Level::kWarn);
    });
    self->stream_.asyncHandshake(asio::ssl::stream_base::server, [self](const error_code& ec) {
      if (self->closed_) return;
      if (ec) {
        self->closeNow("TLS handshake failed: " + net::describeHandshakeError(ec, self->stream_.ssl()),
                       log::Level::kWarn);
        return;
      }
      if (self->stream_.tls()) {
        self->peer_.cert_name = net::peerCommonName(self->stream_.ssl());
        log::debug(log::tag::kLink, self->address_, ": TLS up, robot certificate CN=", self->peer_.cert_name);
      } else {
        log::warn(log::tag::kLink, self->address_, ": UNAUTHENTICATED plaintext connection (--plaintext)");
      }
      self->doRead();
    });
  });
}

void RobotSession::close(std::string reason) {
  asio::post(strand_, [self = shared_from_this(), reason = std::move(reason)] {
    self->closeNow(reason, log::Level::kInfo);
  });
}

void RobotSession::sendCommand(v1::Command cmd) {
  asio::post(strand_, [self = shared_from_this(), cmd = std::move(cmd)] {
    if (self->closed_ || !self->peer_.accepted) return;
    if (cmd.has_stop() || cmd.has_estop()) {
      self->teleop_.active = false;
      ++self->teleop_.generation;
      self->teleop_timer_.cancel();
    }
    v1::Envelope env;
    *env.mutable_command() = cmd;
    self->enqueue(env);
  });
}

void RobotSession::setTeleop(double v_m_s, double w_rad_s, uint64_t first_id, double lease_s) {
  const double lease = lease_s > 0 ? lease_s : 0.0;  // also NaN: no lease
  const auto lapse_at = Clock::now() + std::chrono::duration_cast<Clock::duration>(seconds(lease));
  asio::post(strand_, [self = shared_from_this(), v_m_s, w_rad_s, first_id, lease, lapse_at] {
    if (self->closed_ || !self->peer_.accepted) return;
    self->teleop_.active = true;
    self->teleop_.v_m_s = v_m_s;
    self->teleop_.w_rad_s = w_rad_s;
    self->teleop_.lease_s = lease;
    self->teleop_.lapse_at = lapse_at;
    const uint64_t gen = ++self->teleop_.generation;
    self->teleop_timer_.cancel();
    self->sendTeleopNow(first_id);
    self->teleop_timer_.expires_at(self->nextTeleopAt(Clock::now() + seconds(1.0 / self->config_.teleop_resend_hz)));
    self->armTeleop(gen);
  });
}

RobotSession::Clock::time_point RobotSession::nextTeleopAt(Clock::time_point resend_at) const {
  return teleop_.lease_s > 0 ? std::min(resend_at, teleop_.lapse_at) : resend_at;
}

void RobotSession::lapseTeleop() {
  const double lease_s = teleop_.lease_s;
  teleop_.active = false;
  ++teleop_.generation;
  teleop_.v_m_s = teleop_.w_rad_s = 0.0;
  log::info(log::tag::kLink, who(), ": teleop set-point not renewed for ", fmtShort(lease_s),
            " s: zero set-point sent, re-send stopped");
  sendTeleopNow(server_.nextCommandId());
}

void RobotSession::renewTeleop(double lease_s) {
  if (!(lease_s > 0)) return;
  const auto lapse_at = Clock::now() + std::chrono::duration_cast<Clock::duration>(seconds(lease_s));
  asio::post(strand_, [self = shared_from_this(), lease_s, lapse_at] {
    // The timer fires at the old lapse time at the latest, sees it moved and re-sends.
    if (!self->teleop_.active || self->teleop_.lease_s <= 0) return;
    self->teleop_.lease_s = lease_s;
    self->teleop_.lapse_at = std::max(self->teleop_.lapse_at, lapse_at);
  });
}

void RobotSession::clearTeleop() {
  asio::post(strand_, [self = shared_from_this()] {
    self->teleop_.active = false;
    ++self->teleop_.generation;
    self->teleop_timer_.cancel();
  });
}

void RobotSession::doRead() {
  stream_.asyncReadSome(asio::buffer(rx_buf_),
                          [self = shared_from_this()](const error_code& ec, std::size_t n) { self->onRead(ec, n); });
}

void RobotSession::onRead(const error_code& ec, std::size_t n) {
  if (closed_) return;
  if (peer_.rejecting) {
    // Discard whatever the rejected robot still sends; its closing ends the linger.
    if (ec) closeNow(peer_.reject_reason, log::Level::kDebug);
    else doRead();
    return;
  }
  if (ec) {
    if (ec == asio::error::eof || ec == asio::ssl::error::stream_truncated) {  // TCP FIN without TLS close_notify
      if (decoder_.buffered() > 0)
        closeNow("connection closed in the middle of a frame (" + std::to_string(decoder_.buffered()) +
                     " bytes of an incomplete frame)",
                 log::Level::kWarn);
      else
        closeNow("connection closed by the robot", log::Level::kInfo);
    } else {
      const std::size_t partial = decoder_.buffered();
      closeNow("read error: " + ec.message() +
                   (partial ? " (" + std::to_string(partial) + " bytes of an incomplete frame)" : ""),
               log::Level::kWarn);
    }
    return;
  }
  live_.last_rx = Clock::now();
  decoder_.append(rx_buf_.data(), n);
  for (;;) {
    std::span<const uint8_t> frame;
    const auto st = decoder_.next(frame);
    if (st == net::DelimitedDecoder::Status::kNeedMore) break;
    if (st == net::DelimitedDecoder::Status::kInvalid) {
      closeNow("framing error: " + decoder_.error(), log::Level::kWarn);
      return;
    }
    if (!withinLimits(frame.size())) {
      if (closed_) return;
      continue;  // dropped
    }
    if (!handleFrame(frame)) return;
    if (peer_.rejecting) break;
  }
  doRead();
}

bool RobotSession::handleFrame(std::span<const uint8_t> frame) {
  struct ResetAfter {  // every way out: nothing below keeps a pointer into the frame's message
    google::protobuf::Arena& arena;
    ~ResetAfter() { arena.Reset(); }
  } reset{*rx_arena_};
  v1::Envelope& env = *google::protobuf::Arena::CreateMessage<v1::Envelope>(rx_arena_.get());
  if (!net::DelimitedDecoder::parse(frame, env)) {
    closeNow("malformed frame: " + std::to_string(frame.size()) + " bytes do not parse as inspect.v1.Envelope",
             log::Level::kWarn);
    return false;
  }
  const auto body = env.body_case();
  if (!peer_.accepted) {
    if (body != v1::Envelope::kHello) {
      closeNow(std::string("protocol error: first message must be Hello, got ") + bodyName(body), log::Level::kWarn);
      return false;
    }
    handleHello(env.hello());
    return !closed_;
  }
  switch (body) {
    case v1::Envelope::kHeartbeat:
      return true;  // live_.last_rx already counts it
    case v1::Envelope::kTelemetry: {
      const auto& t = env.telemetry();
      live_.last_telemetry = Clock::now();
      live_.stale_stopped = false;
      live_.robot_moving = t.mode() == v1::TELEOP || t.mode() == v1::TRACKING || t.mode() == v1::NAVIGATING ||
                      t.mode() == v1::WHEEL_TEST || t.cmd_v_m_s() != 0.0 || t.cmd_w_rad_s() != 0.0;
    }
      registry_.onTelemetry(peer_.robot_id, serial_, env.telemetry(), monoNowNs());
      server_.observe(peer_.robot_id, address_, env, true, monoNowUs());
      return true;
    case v1::Envelope::kEvent: {
      uint64_t time_us = monoNowUs();
      if (env.event().has_stored() && !fileStored(env.event().stored(), time_us)) return true;
      const bool late = env.event().has_stored() && env.event().stored().replayed();
      if (late) {
        // The consoles see it as what it is: news from an outage.
        v1::Event shown = env.event();
        shown.set_text(shown.text() + " (stored by the robot, " +
                       fmtShort(static_cast<double>(monoNowUs() - std::min(time_us, monoNowUs())) * 1e-6, 1) +
                       " s ago)");
        registry_.onEvent(peer_.robot_id, serial_, shown, monoNowNs());
      } else {
        registry_.onEvent(peer_.robot_id, serial_, env.event(), monoNowNs());
      }
      server_.observe(peer_.robot_id, address_, env, true, time_us);
      if (server_.logEvents())
        log::info(log::tag::kLink, "[", peer_.robot_id, "] ", v1::Event::Kind_Name(env.event().kind()), ": ",
                  env.event().text(), late ? " (stored by the robot)" : "");
      return true;
    }
    case v1::Envelope::kAck: {
      uint64_t time_us = monoNowUs();
      if (env.ack().has_stored() && !fileStored(env.ack().stored(), time_us)) return true;
      registry_.onAck(peer_.robot_id, serial_, env.ack());
      server_.observe(peer_.robot_id, address_, env, true, time_us);
      return true;
    }
    case v1::Envelope::kHello:
      closeNow("protocol error: second Hello after the handshake", log::Level::kWarn);
      return false;
    case v1::Envelope::kHelloReply:
    case v1::Envelope::kCommand:
    case v1::Envelope::kDelivered:
      closeNow(std::string("protocol error: robot sent a ") + bodyName(body) + ", which only the server sends",
               log::Level::kWarn);
      return false;
    case v1::Envelope::BODY_NOT_SET:
      break;
  }
  closeNow("protocol error: Envelope without a known body (newer protocol?)", log::Level::kWarn);
  return false;
}

void RobotSession::handleHello(const v1::Hello& hello) {
  if (const auto why = helloRejection(hello)) rejectHello(*why);
  else if (stream_.tls() && hello.robot_id() != peer_.cert_name)
    rejectHello("robot id '" + hello.robot_id() + "' does not match its certificate (CN '" + peer_.cert_name +
                "'): a robot may only connect as the id its certificate was made for");
  else acceptHello(hello);
}

void RobotSession::rejectHello(const std::string& reason) {
  log::warn(log::tag::kLink, address_, ": handshake rejected: ", reason);
  handshake_timer_.cancel();
  peer_.rejecting = true;
  peer_.reject_reason = "handshake rejected: " + reason;
  v1::Envelope env;
  auto* r = env.mutable_hello_reply();
  r->set_accepted(false);
  r->set_reason(reason);
  r->set_protocol_version(net::kProtocolVersion);
  r->set_server_id(config_.server_id);
  enqueue(env);
  // Bound the linger: a robot that neither reads nor closes is dropped anyway.
  handshake_timer_.expires_after(kRejectLinger);
  handshake_timer_.async_wait([self = shared_from_this()](const error_code& ec) {
    if (!ec) self->closeNow(self->peer_.reject_reason, log::Level::kDebug);
  });
}

bool RobotSession::fileStored(const v1::Stored& s, uint64_t& time_us) {
  if (peer_.event_stream == 0) return true;  // no stream announced: nothing to de-duplicate against
  const bool fresh = server_.storedEvents().fileOnce(peer_.robot_id, peer_.event_stream, s.seq());
  if (fresh && s.replayed() && peer_.wall_known && s.wall_time_us() > 0) {
    // When it happened, on the server's clock: the robot's UTC time plus
    // the offset measured at the Hello (error: the Hello's one-way delay).
    const int64_t server_wall_us = static_cast<int64_t>(s.wall_time_us()) + peer_.wall_offset_us;
    const int64_t age_us = static_cast<int64_t>(wallNowNs() / 1000) - server_wall_us;
    const int64_t now_us = static_cast<int64_t>(time_us);
    if (age_us > 0 && age_us < now_us) time_us = static_cast<uint64_t>(now_us - age_us);
  }
  v1::Envelope env;
  auto* d = env.mutable_delivered();
  d->set_event_stream(peer_.event_stream);
  d->set_up_to_seq(server_.storedEvents().highest(peer_.robot_id, peer_.event_stream));
  enqueue(env);
  return fresh;
}

void RobotSession::acceptHello(const v1::Hello& hello) {
  handshake_timer_.cancel();
  peer_.accepted = true;
  peer_.robot_id = hello.robot_id();
  peer_.event_stream = hello.event_stream();
  peer_.wall_known = hello.wall_time_us() > 0;
  if (peer_.wall_known)
    peer_.wall_offset_us = static_cast<int64_t>(wallNowNs() / 1000) - static_cast<int64_t>(hello.wall_time_us());
  std::string caps;
  for (const auto& c : hello.capabilities()) caps += (caps.empty() ? "" : ",") + c;
  log::info(log::tag::kLink, peer_.robot_id, " connected from ", address_, " (software '", hello.software_version(),
            "', capabilities [", caps, "])");
  // Attached before the registry says "connected": a console that sees the robot in `robots`
  // (e.g. a script's `expect robots >= 1`) must find its session for the next command.
  server_.attach(peer_.robot_id, shared_from_this());
  if (closed_) return;
  registry_.onConnected(peer_.robot_id, address_, serial_, hello, monoNowNs());
  v1::Envelope env;
  auto* r = env.mutable_hello_reply();
  r->set_accepted(true);
  r->set_protocol_version(net::kProtocolVersion);
  r->set_server_id(config_.server_id);
  enqueue(env);
  heartbeat_timer_.expires_after(std::chrono::nanoseconds(0));
  armHeartbeat();
  armWatchdog();
  live_.last_telemetry = Clock::now();
  if (config_.telemetry_stale_s > 0) armStaleCheck();
}

void RobotSession::armWatchdog() {
  watchdog_timer_.expires_at(live_.last_rx + seconds(config_.session_timeout_s));
  watchdog_timer_.async_wait([self = shared_from_this()](const error_code& ec) {
    if (ec || self->closed_) return;
    if (Clock::now() - self->live_.last_rx >= seconds(self->config_.session_timeout_s)) {
      self->closeNow("nothing received for " + fmtShort(self->config_.session_timeout_s) +
                         " s (session timeout: robot gone or link half-open)",
                     log::Level::kWarn);
      return;
    }
    self->armWatchdog();
  });
}

// The operator is blind to a robot whose telemetry stopped while it moves
// (e.g. the robot->server direction stalled while commands still arrive, so
// the robot's own link timeout does not fire): e-stop it, once per gap. The
// EStop zeroes the wheels at once (a Stop ramps down) and is latched: the
// operator resumes once the robot is visible again (no automatic restart).
// The timer wakes when the last telemetry turns stale, not on a fixed tick:
// with telemetry flowing, once per telemetry_stale_s (a 20 ms tick was 5,000
// wake-ups a second for 100 robots, docs/load.md); inside a gap every 20 ms,
// since a set-point may start there.
void RobotSession::armStaleCheck() {
  const auto stale_at = live_.last_telemetry + seconds(config_.telemetry_stale_s);
  const auto now = Clock::now();
  stale_timer_.expires_at(stale_at > now ? stale_at : now + std::chrono::milliseconds(20));
  stale_timer_.async_wait([self = shared_from_this()](const error_code& ec) {
    if (ec || self->closed_) return;
    const auto gap = Clock::now() - self->live_.last_telemetry;
    if (!self->live_.stale_stopped && (self->live_.robot_moving || self->teleop_.active) &&
        gap >= seconds(self->config_.telemetry_stale_s)) {
      self->live_.stale_stopped = true;
      self->teleop_.active = false;
      ++self->teleop_.generation;
      self->teleop_timer_.cancel();
      const std::string why = "no telemetry for " + fmtShort(std::chrono::duration<double>(gap).count(), 2) +
                              " s while moving: EStop sent (the operator cannot see the robot; resume once it is "
                              "back)";
      log::warn(log::tag::kLink, self->who(), ": ", why);
      v1::Envelope env;
      env.mutable_command()->set_id(self->server_.nextCommandId());
      env.mutable_command()->mutable_estop();
      self->enqueue(env);
      v1::Event ev;  // shown on every console like the robot's own events
      ev.set_kind(v1::Event::FAULT_RAISED);
      ev.set_text("server: " + why);
      self->registry_.onEvent(self->peer_.robot_id, self->serial_, ev, monoNowNs());
    }
    self->armStaleCheck();
  });
}

void RobotSession::armHeartbeat() {
  heartbeat_timer_.async_wait([self = shared_from_this()](const error_code& ec) {
    if (ec || self->closed_) return;
    v1::Envelope env;
    env.mutable_heartbeat()->set_time_us(monoNowUs());
    self->enqueue(env);
    if (self->closed_) return;
    const auto period = seconds(self->config_.heartbeat_period_s);
    auto next = self->heartbeat_timer_.expiry() + period;
    if (next < Clock::now()) next = Clock::now() + period;  // fell behind: do not burst
    self->heartbeat_timer_.expires_at(next);
    self->armHeartbeat();
  });
}

void RobotSession::armTeleop(uint64_t generation) {
  teleop_timer_.async_wait([self = shared_from_this(), generation](const error_code& ec) {
    if (ec || self->closed_ || !self->teleop_.active || generation != self->teleop_.generation) return;
    if (!self->server_.consoleResponsive()) {
      // The robot's own 300 ms deadman takes it from here.
      self->teleop_.active = false;
      log::warn(log::tag::kLink, self->who(), ": console unresponsive: teleop set-point cleared, re-send stopped");
      return;
    }
    if (self->teleop_.lease_s > 0 && Clock::now() >= self->teleop_.lapse_at) {
      self->lapseTeleop();
      return;
    }
    self->sendTeleopNow(self->server_.nextCommandId());
    if (self->closed_) return;
    const auto period = seconds(1.0 / self->config_.teleop_resend_hz);
    auto next = self->teleop_timer_.expiry() + period;
    if (next < Clock::now()) next = Clock::now() + period;
    self->teleop_timer_.expires_at(self->nextTeleopAt(next));
    self->armTeleop(generation);
  });
}

void RobotSession::sendTeleopNow(uint64_t id) {
  v1::Envelope env;
  auto* c = env.mutable_command();
  c->set_id(id);
  c->mutable_teleop()->set_v_m_s(teleop_.v_m_s);
  c->mutable_teleop()->set_w_rad_s(teleop_.w_rad_s);
  enqueue(env);
}

void RobotSession::enqueue(v1::Envelope& env) {
  if (closed_) return;
  env.set_seq(++tx_.seq);
  env.set_send_time_us(monoNowUs());
  std::string frame;
  if (!net::appendDelimited(env, frame)) {
    log::error(log::tag::kLink, who(), ": cannot serialise an outgoing ", bodyName(env.body_case()));
    return;
  }
  if (tx_.bytes + frame.size() > kMaxQueuedBytes) {
    closeNow("more than " + std::to_string(kMaxQueuedBytes) + " bytes waiting to be sent: the robot is not reading",
             log::Level::kWarn);
    return;
  }
  tx_.bytes += frame.size();
  if (peer_.accepted && env.has_command()) server_.observe(peer_.robot_id, address_, env, false, env.send_time_us());
  const bool idle = tx_.queue.empty();
  tx_.queue.push_back(std::move(frame));
  if (idle) doWrite();
}

void RobotSession::doWrite() {
  stream_.asyncWrite(asio::buffer(tx_.queue.front()),
                    [self = shared_from_this()](const error_code& ec, std::size_t) { self->onWrite(ec); });
}

void RobotSession::onWrite(const error_code& ec) {
  if (closed_) return;
  if (ec) {
    closeNow("write error: " + ec.message(), log::Level::kWarn);
    return;
  }
  tx_.bytes -= tx_.queue.front().size();
  tx_.queue.pop_front();
  if (!tx_.queue.empty()) {
    doWrite();
  } else if (peer_.rejecting) {
    // The reply is out: half-close so the robot reads it and sees EOF; its close ends the linger.
    error_code ignored;
    stream_.socket().shutdown(asio::ip::tcp::socket::shutdown_send, ignored);
  }
}

void RobotSession::closeNow(const std::string& reason, log::Level level) {
  if (closed_) return;
  closed_ = true;
  teleop_.active = false;
  log::logf(level, log::tag::kLink, who(), ": closed: ", reason);
  handshake_timer_.cancel();
  watchdog_timer_.cancel();
  heartbeat_timer_.cancel();
  teleop_timer_.cancel();
  stale_timer_.cancel();
  stream_.close();
  if (peer_.accepted) registry_.onDisconnected(peer_.robot_id, serial_, reason, monoNowNs());
  server_.detach(shared_from_this(), peer_.robot_id);
}

}  // namespace inspect::server
