#include "tests/support/fake_robot/fleet_robot.hpp"

#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>

#include "shared/net/link_version.hpp"
#include "shared/util/clock.hpp"
#include "tests/support/fake_robot/robot_messages.hpp"

namespace inspect::test {

namespace asio = boost::asio;
using asio::ip::tcp;
using boost::system::error_code;

namespace {
constexpr double kWheelRadius = 0.200;  // config/robot.yaml geometry
constexpr double kTrack = 0.438;
constexpr std::size_t kFloodBatch = 64;

}  // namespace

std::string robotId(const std::string& prefix, int index) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%03d", index);
  return prefix + buf;
}

FleetRobot::FleetRobot(asio::io_context& ioc, FleetRobotOptions options)
    : options_(std::move(options)),
      strand_(asio::make_strand(ioc)),
      hb_timer_(strand_),
      tlm_timer_(strand_),
      rng_(options_.seed) {}

FleetRobot::~FleetRobot() = default;

std::string FleetRobot::closeReason() const {
  std::lock_guard lk(info_mu_);
  return close_reason_;
}

std::string FleetRobot::localAddress() const {
  std::lock_guard lk(info_mu_);
  return local_address_;
}

void FleetRobot::start() {
  const std::string& d = options_.certs_dir;
  tls_ = net::makeTlsContext({d + "/ca.pem", d + "/" + options_.id + ".pem", d + "/" + options_.id + ".key"},
                             net::TlsRole::kClient);
  stream_ = std::make_unique<net::LinkStream>(tcp::socket(strand_), tls_);
  stream_->expectServerName("127.0.0.1");
  const tcp::endpoint ep(asio::ip::make_address("127.0.0.1"), options_.port);
  stream_->socket().async_connect(ep, [self = shared_from_this()](const error_code& ec) { self->onConnected(ec); });
}

FleetRobot::TcpBytes FleetRobot::tcpBytes() const {
  TcpBytes b;
  const int fd = fd_;
  if (fd < 0) return b;
  // struct tcp_info of <linux/tcp.h> (append-only kernel ABI): tcpi_bytes_acked at
  // offset 120, tcpi_bytes_received at 128 (Linux >= 4.1). glibc's copy stops earlier.
  alignas(8) unsigned char info[256] = {};
  socklen_t len = sizeof info;
  if (::getsockopt(fd, IPPROTO_TCP, TCP_INFO, info, &len) != 0 || len < 136) return b;
  std::memcpy(&b.sent_acked, info + 120, 8);
  std::memcpy(&b.received, info + 128, 8);
  return b;
}

void FleetRobot::onConnected(const error_code& ec) {
  if (ec) return fail("connect: " + ec.message());
  error_code ignored;
  stream_->socket().set_option(tcp::no_delay(true), ignored);
  fd_ = stream_->socket().native_handle();
  {
    const auto le = stream_->socket().local_endpoint(ignored);
    std::lock_guard lk(info_mu_);
    local_address_ = le.address().to_string() + ":" + std::to_string(le.port());
  }
  stream_->asyncHandshake(asio::ssl::stream_base::client, [self = shared_from_this()](const error_code& e) {
    if (e) return self->fail("TLS handshake: " + net::describeHandshakeError(e, self->stream_->ssl()));
    self->up_ = true;
    v1::Envelope env;
    *env.mutable_hello() = fullHello(self->options_.id, "link_load sim robot");
    self->queue(env);
    self->doRead();
  });
}

void FleetRobot::doRead() {
  stream_->asyncReadSome(asio::buffer(rx_buf_),
                         [self = shared_from_this()](const error_code& ec, std::size_t n) { self->onRead(ec, n); });
}

void FleetRobot::onRead(const error_code& ec, std::size_t n) {
  if (!up_) return;
  if (ec) {
    if (ec == asio::error::eof || ec == asio::ssl::error::stream_truncated) return fail("closed by the server");
    return fail("read: " + ec.message());
  }
  stats_.app_bytes_received += n;
  decoder_.append(rx_buf_.data(), n);
  for (;;) {
    std::span<const uint8_t> frame;
    const auto st = decoder_.next(frame);
    if (st == net::DelimitedDecoder::Status::kNeedMore) break;
    v1::Envelope env;
    if (st == net::DelimitedDecoder::Status::kInvalid || !net::DelimitedDecoder::parse(frame, env))
      return fail("bad frame from the server");
    handle(env);
    if (!up_) return;
  }
  doRead();
}

void FleetRobot::handle(const v1::Envelope& env) {
  if (env.has_hello_reply()) {
    if (!env.hello_reply().accepted()) {
      stats_.rejected = true;
      return fail("rejected: " + env.hello_reply().reason());
    }
    stats_.accepted = true;
    last_hb_rx_ = Clock::now();
    hb_timer_.expires_after(std::chrono::milliseconds(0));
    armHeartbeat();
  } else if (env.has_heartbeat()) {
    const auto now = Clock::now();
    if (reset_gap_.exchange(false)) stats_.max_heartbeat_gap_us = 0;
    else {
      const int64_t gap = std::chrono::duration_cast<std::chrono::microseconds>(now - last_hb_rx_).count();
      if (gap > stats_.max_heartbeat_gap_us) stats_.max_heartbeat_gap_us = gap;
    }
    last_hb_rx_ = now;
    ++stats_.heartbeats_received;
  } else if (env.has_command()) {
    ++stats_.commands_received;
    v1::Envelope a;
    *a.mutable_ack() = acceptedAck(env.command());
    queue(a);
    ++stats_.acks_sent;
  }
}

void FleetRobot::armHeartbeat() {
  hb_timer_.async_wait([self = shared_from_this()](const error_code& ec) {
    if (ec || !self->up_) return;
    v1::Envelope env;
    env.mutable_heartbeat()->set_time_us(monoNowUs());
    self->queue(env);
    ++self->stats_.heartbeats_sent;
    const auto period = std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(self->options_.heartbeat_period_s));
    auto next = self->hb_timer_.expiry() + period;
    if (next < Clock::now()) next = Clock::now() + period;
    self->hb_timer_.expires_at(next);
    self->armHeartbeat();
  });
}

void FleetRobot::startTelemetry() {
  asio::post(strand_, [self = shared_from_this()] {
    if (self->telemetry_on_ || self->options_.telemetry_hz <= 0) return;
    self->telemetry_on_ = true;
    const uint64_t gen = ++self->tlm_generation_;
    // Robots are not synchronised: each starts at a random phase of the period.
    const double period_s = 1.0 / self->options_.telemetry_hz;
    std::uniform_real_distribution<double> phase(0.0, period_s);
    self->tlm_timer_.expires_after(
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(phase(self->rng_))));
    self->armTelemetry(gen);
  });
}

void FleetRobot::stopTelemetry() {
  asio::post(strand_, [self = shared_from_this()] {
    self->telemetry_on_ = false;
    ++self->tlm_generation_;
    self->tlm_timer_.cancel();
  });
}

void FleetRobot::armTelemetry(uint64_t generation) {
  tlm_timer_.async_wait([self = shared_from_this(), generation](const error_code& ec) {
    if (ec || !self->up_ || generation != self->tlm_generation_) return;
    self->sendTelemetryNow();
    const auto period = std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(1.0 / self->options_.telemetry_hz));
    auto next = self->tlm_timer_.expiry() + period;
    if (next < Clock::now()) next = Clock::now() + period;  // fell behind: no burst
    self->tlm_timer_.expires_at(next);
    self->armTelemetry(generation);
  });
}

void FleetRobot::sendTelemetryNow() {
  const uint64_t now_us = monoNowUs();
  fillTelemetry(*tlm_env_.mutable_telemetry(), now_us);
  tlm_env_.set_send_time_us(now_us);
  queue(tlm_env_);
}

void FleetRobot::fillTelemetry(v1::Telemetry& t, uint64_t now_us) {
  const uint64_t n = ++stats_.telemetry_sent;
  t_s_ += 1.0 / std::max(1.0, options_.telemetry_hz);
  // Driving a 2 m circle at 0.3 m/s with a person nearby now and then; sensor noise on top.
  const double v = 0.3, w = v / 2.0;
  const double th = std::remainder(w * t_s_, 2 * M_PI);
  const double wl = (v - w * kTrack / 2) / kWheelRadius, wr = (v + w * kTrack / 2) / kWheelRadius;
  t.set_robot_time_us(now_us);
  auto* p = t.mutable_pose();
  p->set_x_m(2.0 * std::sin(w * t_s_));
  p->set_y_m(2.0 * (1 - std::cos(w * t_s_)));
  p->set_theta_rad(th);
  t.set_wheel_left_rad_s(wl + 0.01 * noise_(rng_));
  t.set_wheel_right_rad_s(wr + 0.01 * noise_(rng_));
  t.set_cmd_wheel_left_rad_s(wl);
  t.set_cmd_wheel_right_rad_s(wr);
  t.set_v_m_s(v + 0.002 * noise_(rng_));
  t.set_w_rad_s(w + 0.002 * noise_(rng_));
  t.set_cmd_v_m_s(v);
  t.set_cmd_w_rad_s(w);
  t.clear_ultrasonic_m();
  t.add_ultrasonic_m(1.5 + 0.5 * std::sin(t_s_) + 0.03 * noise_(rng_));
  t.add_ultrasonic_m(1.8 + 0.5 * std::cos(t_s_) + 0.03 * noise_(rng_));
  t.add_ultrasonic_m(std::fmod(t_s_, 10.0) < 5.0 ? 0.9 + 0.03 * noise_(rng_) : -1.0);
  t.add_ultrasonic_m(2.4 + 0.03 * noise_(rng_));
  t.set_grayscale(n % 200 < 20 ? 0x18u : 0u);
  t.clear_gas();
  t.add_gas(std::max(0.0, 1.5 + 0.3 * noise_(rng_)));   // CH4 %LEL
  t.add_gas(std::max(0.0, 0.4 + 0.2 * noise_(rng_)));   // H2S ppm
  t.add_gas(std::max(0.0, 3.0 + 1.0 * noise_(rng_)));   // CO ppm
  t.add_gas(20.9 + 0.03 * noise_(rng_));                // O2 %vol
  t.set_battery_v(25.2 - 1e-4 * t_s_);
  t.set_mode(v1::NAVIGATING);
  t.set_faults(0);
  t.set_mcu_faults(0);
  auto* s = t.mutable_serial();
  s->set_frames_ok(n);  // the telemetry sequence number (see the header)
  s->set_bytes_rx(n * 46);
  s->set_bytes_tx(n * 19);
  s->set_frames_tx(n);
  t.set_sensor_rate_hz(100.0);
  t.set_last_command_id(0);
  auto* ref = t.mutable_reference();
  ref->set_x_m(p->x_m());
  ref->set_y_m(p->y_m());
  ref->set_theta_rad(th);
  t.set_position_error_m(0.01 + 0.002 * std::abs(noise_(rng_)));
  t.set_angle_error_rad(0.005 + 0.001 * std::abs(noise_(rng_)));
  t.set_kp(9.1);
  t.set_ki(2.05);
  t.set_kd(2.9);
  t.set_pattern(std::fmod(t_s_, 10.0) < 5.0 ? v1::CROSSING : v1::PATTERN_NONE);
  t.set_nearest_person_m(std::fmod(t_s_, 10.0) < 5.0 ? 0.9 : -1.0);
  t.set_nearest_person_speed_m_s(std::fmod(t_s_, 10.0) < 5.0 ? 0.8 : 0.0);
  t.set_speed_factor(std::fmod(t_s_, 10.0) < 5.0 ? 0.6 : 1.0);
  t.set_people_tracked(std::fmod(t_s_, 10.0) < 5.0 ? 1 : 0);
  t.set_nav_mode("GO_TO_GOAL");
  t.set_goal_distance_m(1.2);
  t.set_goal_index(2);
  t.set_goal_count(6);
  t.set_nav_switches(3);
  auto* vs = t.mutable_video();  // robot_client reports its camera even with the stream off
  vs->set_enabled(false);
  vs->set_ssrc(0x1234abcd);
  vs->set_width(640);
  vs->set_height(480);
  vs->set_fps(30);
  vs->set_bitrate_kbps(1500);
  vs->set_encoder("libx264");
  vs->set_source("synthetic");
  vs->set_port(5600);
  t.set_ptz_pan_rad(0.0);
  t.set_ptz_tilt_rad(-0.2);
  t.set_waypoint_label("valve V3");
  t.set_gains_version(0);
  t.set_mcu_time_us(n * 10000);
}

void FleetRobot::flood(std::chrono::milliseconds duration) {
  asio::post(strand_, [self = shared_from_this(), duration] {
    self->flood_until_ = Clock::now() + duration;
    self->flushWrites();
  });
}

void FleetRobot::sendEvent(const std::string& text) {
  asio::post(strand_, [self = shared_from_this(), text] {
    v1::Envelope env;
    env.mutable_event()->set_kind(v1::Event::INFO);
    env.mutable_event()->set_text(text);
    env.mutable_event()->set_robot_time_us(monoNowUs());
    self->queue(env);
  });
}

void FleetRobot::sendAlarmTransition() {
  asio::post(strand_, [self = shared_from_this()] {
    const bool raise = !self->alarm_active_;
    if (raise) ++self->alarm_id_;
    self->alarm_active_ = raise;
    v1::Envelope env;
    auto* e = env.mutable_event();
    const uint64_t now_us = monoNowUs();
    e->set_kind(raise ? v1::Event::ALARM_RAISED : v1::Event::ALARM_CLEARED);
    e->set_robot_time_us(now_us);
    auto* a = e->mutable_gas_alarm();
    a->set_id(self->alarm_id_);
    a->set_channel(0);
    a->set_channel_name("CH4");
    a->set_level(v1::GasAlarm::LOW);
    a->set_active(raise);
    a->set_value(raise ? 12.0 : 8.0);
    a->set_threshold(10.0);
    a->set_unit("%LEL");
    a->set_robot_time_us(now_us);
    self->queue(env);
    ++self->stats_.alarm_transitions_sent;
  });
}

void FleetRobot::queue(v1::Envelope& env) {
  if (!up_) return;
  env.set_seq(++tx_seq_);
  if (!env.has_telemetry()) env.set_send_time_us(monoNowUs());
  const std::size_t before = pending_.size();
  if (!net::appendDelimited(env, pending_)) return fail("cannot serialise");
  stats_.app_bytes_sent += pending_.size() - before;
  if (writing_ && static_cast<int64_t>(pending_.size()) > stats_.max_write_backlog)
    stats_.max_write_backlog = static_cast<int64_t>(pending_.size());
  if (!writing_) flushWrites();
}

void FleetRobot::flushWrites() {
  if (!up_ || writing_) return;
  if (pending_.empty() && Clock::now() < flood_until_) {
    for (std::size_t i = 0; i < kFloodBatch; ++i) {
      const uint64_t now_us = monoNowUs();
      fillTelemetry(*tlm_env_.mutable_telemetry(), now_us);
      tlm_env_.set_send_time_us(now_us);
      tlm_env_.set_seq(++tx_seq_);
      const std::size_t before = pending_.size();
      net::appendDelimited(tlm_env_, pending_);
      stats_.app_bytes_sent += pending_.size() - before;
    }
  }
  if (pending_.empty()) return;
  inflight_.swap(pending_);
  pending_.clear();
  writing_ = true;
  stream_->asyncWrite(asio::buffer(inflight_), [self = shared_from_this()](const error_code& ec, std::size_t) {
    self->writing_ = false;
    self->inflight_.clear();
    if (!self->up_) return;
    if (ec) return self->fail("write: " + ec.message());
    self->flushWrites();
  });
}

void FleetRobot::fail(const std::string& why) {
  if (stats_.closed) return;
  {
    std::lock_guard lk(info_mu_);
    close_reason_ = why;
  }
  stats_.closed = true;
  up_ = false;
  fd_ = -1;
  hb_timer_.cancel();
  tlm_timer_.cancel();
  if (stream_) stream_->close();
}

void FleetRobot::close() {
  asio::post(strand_, [self = shared_from_this()] { self->fail("closed by us"); });
}

}  // namespace inspect::test
