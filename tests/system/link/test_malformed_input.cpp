// Malformed input, a telemetry flood and slow connections against the real
// pc_server (mutual TLS, 127.0.0.1, ephemeral port, recording on) while three
// good robots stream telemetry at 100 Hz throughout. The server must stay up,
// log a clear reason for every attacker connection it closes, drop slow
// connections at the handshake timeout, and the good robots must lose
// nothing: every telemetry sequence number they sent is in their recorded
// runs exactly once, their sessions never close and the server's heartbeats
// keep coming. docs/load.md lists the attacks.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>

#include "tests/support/process.hpp"
#include "tests/system/link/attack_conn.hpp"
#include "tests/system/link/server_harness.hpp"
#include "tests/support/fake_robot/fleet_robot.hpp"
#include "tests/support/test_certs.hpp"

namespace inspect::linktest {
namespace {

namespace asio = boost::asio;
using test::FleetRobot;
using test::FleetRobotOptions;
using test::robotId;
using Clock = std::chrono::steady_clock;

constexpr double kHandshakeTimeout = 2.0;  // the test's server config (default 5 s)
constexpr int kGood = 3;
constexpr int kSlowSilent = 50;      // connect, then nothing
constexpr int kSlowTrickle = 50;     // a byte of a TLS ClientHello every second
constexpr int kSlowNoHello = 10;     // TLS done, then nothing
constexpr int kSlowHelloTrickle = 5; // TLS done, a Hello one byte per second

/// An io_context with one thread of its own.
struct IoThread {
  asio::io_context ioc{1};
  asio::executor_work_guard<asio::io_context::executor_type> guard = asio::make_work_guard(ioc);
  std::thread thread{[this] { ioc.run(); }};
  ~IoThread() { stop(); }
  void stop() {
    guard.reset();
    ioc.stop();
    if (thread.joinable()) thread.join();
  }
};

/// One attacker connection and what the server's log must say about it.
struct Attack {
  std::string name;
  std::string local;                  // 127.0.0.1:port, as the server logs it
  std::vector<std::string> expect;    // one of these in the log line about this connection
  std::optional<double> closed_after; // s from connect until the server closed it
  bool attacker_closes = false;       // the attacker hangs up itself: only the log line tells
  std::string note;                   // setup problems
};

std::string randomBytes(std::mt19937& rng, std::size_t n) {
  std::string s(n, '\0');
  for (auto& c : s) c = static_cast<char>(rng() & 0xff);
  return s;
}

/// The log line about connection `local` that contains one of `expect`; "" if none.
std::string logLineFor(const std::string& log, const std::string& local, const std::vector<std::string>& expect) {
  std::istringstream in(log);
  std::string line;
  while (std::getline(in, line)) {
    const bool about = line.find(local + ":") != std::string::npos || line.find(local + ")") != std::string::npos;
    if (!about) continue;
    for (const auto& e : expect)
      if (line.find(e) != std::string::npos) return line;
  }
  return "";
}

class LinkAttackTest : public ::testing::Test {
 protected:
  void SetUp() override {
    for (int i = 1; i <= kGood; ++i) good_ids_.push_back(robotId("good", i));
    std::vector<std::string> ids = good_ids_;
    for (int i = 1; i <= 30; ++i) ids.push_back(robotId("evil", i));
    ids.push_back("flood001");
    ids.push_back("late001");
    certs_ = test::testCertsDir(ids);
    const std::string cfg = dir_ / "server.yaml";
    // The per-robot limits at their defaults but for the time to close a
    // session that keeps on flooding (5 s; the flood lasts 3 s).
    test::writeFile(cfg, "handshake_timeout_s: 2.0   # slow connections are dropped after this\n"
                         "robot_limits:\n  close_after_s: 2.0\n");
    ASSERT_TRUE(server_.start({dir_.path(), certs_, cfg, {}})) << server_.error();
  }
  void TearDown() override {
    if (HasFailure()) {
      const std::string log = server_.log();
      std::fprintf(stderr, "---- server log (last 12000 bytes) ----\n%s\n",
                   log.size() > 12000 ? log.substr(log.size() - 12000).c_str() : log.c_str());
    }
  }

  /// A connection as robot `evil<n>` (TLS + accepted Hello); false with a note.
  bool evilRobot(AttackConn& c, Attack& a, bool hello = true) {
    const std::string id = robotId("evil", ++evil_);
    if (!c.connect(server_.port())) return a.note = "connect failed", false;
    a.local = c.local();
    if (!c.handshake(certs_, id)) return a.note = c.tlsError(), false;
    if (hello && !c.hello(id)) return a.note = "Hello of " + id + " not accepted", false;
    return true;
  }

  test::TempDir dir_{"link_attack"};
  std::string certs_;
  std::vector<std::string> good_ids_;
  ServerUnderTest server_;
  int evil_ = 0;
};

TEST_F(LinkAttackTest, ServerSurvivesAndGoodRobotsLoseNothing) {
  const auto t_start = Clock::now();
  std::mt19937 rng(20240509);

  // ---- three good robots, recorded, telemetry at 100 Hz throughout ----
  IoThread good_io;
  std::vector<std::shared_ptr<FleetRobot>> good;
  for (int i = 0; i < kGood; ++i) {
    FleetRobotOptions o;
    o.id = good_ids_[static_cast<std::size_t>(i)];
    o.certs_dir = certs_;
    o.port = server_.port();
    o.telemetry_hz = 100;
    o.seed = static_cast<uint32_t>(7 + i);
    good.push_back(std::make_shared<FleetRobot>(good_io.ioc, o));
    good.back()->start();
  }
  ASSERT_TRUE(test::waitUntil(
      [&] { return std::all_of(good.begin(), good.end(), [](const auto& r) { return r->stats().accepted.load(); }); },
      10.0))
      << good[0]->closeReason();
  ASSERT_TRUE(server_.recordStart(good_ids_, "attack", 10.0)) << server_.out();
  for (auto& r : good) r->startTelemetry();
  test::sleepS(1.0);
  for (auto& r : good) r->resetHeartbeatGap();
  const auto mem0 = sampleProc(server_.pid());

  std::vector<Attack> attacks;

  // ---- slow connections, in the background: never finish the TLS handshake or the Hello ----
  std::vector<Attack> slow(kSlowSilent + kSlowTrickle + kSlowNoHello + kSlowHelloTrickle);
  std::thread slow_thread([&] {
    std::vector<std::unique_ptr<AttackConn>> conns;
    // The first bytes of a TLS 1.2 ClientHello record.
    const std::string client_hello_start("\x16\x03\x01\x02\x00\x01\x00\x01\xfc\x03\x03", 11);
    std::string hello_wire;
    {
      v1::Envelope e;
      e.set_seq(1);
      e.mutable_hello()->set_robot_id("evil030");
      e.mutable_hello()->set_protocol_version(net::kProtocolVersion);
      net::appendDelimited(e, hello_wire);
    }
    for (std::size_t i = 0; i < slow.size(); ++i) {
      auto c = std::make_unique<AttackConn>();
      Attack& a = slow[i];
      const bool tls = i >= static_cast<std::size_t>(kSlowSilent + kSlowTrickle);
      a.name = i < kSlowSilent                   ? "slow: silent before TLS"
               : i < kSlowSilent + kSlowTrickle ? "slow: ClientHello a byte per second"
               : i < slow.size() - kSlowHelloTrickle ? "slow: TLS, then no Hello"
                                                     : "slow: TLS, Hello a byte per second";
      a.expect = {tls ? "closed: no Hello within 2 s (handshake timeout)"
                      : "closed: no TLS handshake within 2 s (handshake timeout)"};
      if (!c->connect(server_.port())) a.note = "connect failed";
      a.local = c->local();
      if (tls && !c->handshake(certs_, "evil030")) a.note = c->tlsError();
      conns.push_back(std::move(c));
    }
    // Trickle, watch for the server's close; bounded at handshake timeout + 4 s.
    const auto deadline = Clock::now() + std::chrono::duration<double>(kHandshakeTimeout + 4.0);
    std::size_t open = conns.size();
    int second = 0;
    auto next_byte = Clock::now();
    while (open > 0 && Clock::now() < deadline) {
      if (Clock::now() >= next_byte) {
        const std::size_t trickle_end = kSlowSilent + kSlowTrickle;
        const std::size_t hello_trickle_begin = trickle_end + kSlowNoHello;
        for (std::size_t i = kSlowSilent; i < conns.size(); ++i) {
          if (slow[i].closed_after || !slow[i].note.empty()) continue;
          const auto at = static_cast<std::size_t>(second);
          if (i < trickle_end && at < client_hello_start.size()) conns[i]->sendRaw(client_hello_start.substr(at, 1));
          if (i >= hello_trickle_begin && at < hello_wire.size()) conns[i]->sendTls(hello_wire.substr(at, 1));
        }
        ++second;
        next_byte += std::chrono::seconds(1);
      }
      std::vector<pollfd> fds;
      std::vector<std::size_t> which;
      for (std::size_t i = 0; i < conns.size(); ++i)
        if (!slow[i].closed_after && conns[i]->fd() >= 0) {
          fds.push_back({conns[i]->fd(), POLLIN, 0});
          which.push_back(i);
        }
      if (fds.empty()) break;
      if (::poll(fds.data(), fds.size(), 50) <= 0) continue;
      for (std::size_t k = 0; k < fds.size(); ++k) {
        if (!(fds[k].revents & (POLLIN | POLLHUP | POLLERR))) continue;
        char buf[4096];
        const auto n = ::recv(fds[k].fd, buf, sizeof buf, MSG_DONTWAIT);
        if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
          const std::size_t i = which[k];
          slow[i].closed_after = std::chrono::duration<double>(Clock::now() - conns[i]->connectedAt()).count();
          conns[i]->close();
          --open;
        }
      }
    }
  });

  // ---- malformed input, one connection each, while the slow ones hang on ----
  auto run = [&](const std::string& name, std::vector<std::string> expect, auto&& body) {
    Attack a;
    a.name = name;
    a.expect = std::move(expect);
    AttackConn c;
    body(c, a);
    if (a.note.empty() && !a.attacker_closes) a.closed_after = c.waitClosedByServer(4.0);
    attacks.push_back(a);
  };
  const std::vector<std::string> kGarbageReasons = {"closed: framing error", "closed: malformed frame",
                                                    "closed: protocol error", "closed: no Hello within",
                                                    "closed: nothing received for"};

  run("random bytes before the TLS handshake", {"closed: TLS handshake failed"}, [&](AttackConn& c, Attack& a) {
    if (!c.connect(server_.port())) return void(a.note = "connect failed");
    a.local = c.local();
    c.sendRaw(randomBytes(rng, 2048));
  });
  run("an HTTP request instead of TLS", {"closed: TLS handshake failed"}, [&](AttackConn& c, Attack& a) {
    if (!c.connect(server_.port())) return void(a.note = "connect failed");
    a.local = c.local();
    c.sendRaw("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
  });
  run("a plaintext Hello (robot without TLS)", {"closed: TLS handshake failed"}, [&](AttackConn& c, Attack& a) {
    if (!c.connect(server_.port())) return void(a.note = "connect failed");
    a.local = c.local();
    v1::Envelope e;
    e.mutable_hello()->set_robot_id("good001");
    e.mutable_hello()->set_protocol_version(net::kProtocolVersion);
    std::string wire;
    net::appendDelimited(e, wire);
    c.sendRaw(wire);
  });
  run("random bytes inside TLS before the Hello", kGarbageReasons, [&](AttackConn& c, Attack& a) {
    if (evilRobot(c, a, false)) c.sendTls(randomBytes(rng, 4096));
  });
  run("oversize length prefix (2 GiB) before the Hello",
      {"closed: framing error: frame of 2147483648 bytes exceeds the maximum of 1048576"},
      [&](AttackConn& c, Attack& a) {
        if (evilRobot(c, a, false)) c.sendTls(varint(1ull << 31) + std::string(16, 'x'));
      });
  run("oversize length prefix (1 MiB + 1) after the Hello",
      {"closed: framing error: frame of 1048577 bytes exceeds the maximum of 1048576"},
      [&](AttackConn& c, Attack& a) {
        if (evilRobot(c, a)) c.sendTls(varint((1u << 20) + 1) + std::string(100, 'x'));
      });
  run("length prefix 2^64-1 after the Hello", {"closed: framing error"}, [&](AttackConn& c, Attack& a) {
    if (evilRobot(c, a)) c.sendTls(varint(~0ull));
  });
  run("length varint of 11 bytes after the Hello", {"closed: framing error: length varint"},
      [&](AttackConn& c, Attack& a) {
        if (evilRobot(c, a)) c.sendTls(std::string(11, '\xff'));
      });
  run("truncated frame, then TLS close_notify (after the Hello)",
      {"closed: connection closed in the middle of a frame"}, [&](AttackConn& c, Attack& a) {
        if (!evilRobot(c, a)) return;
        c.sendTls(varint(300) + std::string(100, '\x08'));
        test::sleepS(0.05);
        a.attacker_closes = true;
        c.closeNotify();
      });
  run("truncated frame, then TCP close without close_notify (before the Hello)",
      {"closed: connection closed in the middle of a frame"}, [&](AttackConn& c, Attack& a) {
        if (!evilRobot(c, a, false)) return;
        c.sendTls(varint(300) + std::string(10, '\x08'));
        test::sleepS(0.05);
        a.attacker_closes = true;
        c.drainRaw();  // a FIN, not a reset for unread data
        c.close();
      });
  run("Envelope with only an unknown field (a newer body type) after the Hello",
      {"closed: protocol error: Envelope without a known body"}, [&](AttackConn& c, Attack& a) {
        if (!evilRobot(c, a)) return;
        // seq = 9, then field 99 (varint) = 7: valid protobuf, no body this protocol knows.
        const std::string msg = std::string("\x08\x09", 2) + varint((99u << 3) | 0) + "\x07";
        c.sendTls(varint(msg.size()) + msg);
      });
  run("empty Envelope after the Hello", {"closed: protocol error: Envelope without a known body"},
      [&](AttackConn& c, Attack& a) {
        if (evilRobot(c, a)) c.sendTls(varint(0));
      });
  run("empty Envelope instead of the Hello", {"closed: protocol error: first message must be Hello"},
      [&](AttackConn& c, Attack& a) {
        if (evilRobot(c, a, false)) c.sendTls(varint(0));
      });
  run("Telemetry instead of the Hello", {"closed: protocol error: first message must be Hello, got Telemetry"},
      [&](AttackConn& c, Attack& a) {
        if (!evilRobot(c, a, false)) return;
        v1::Envelope e;
        e.mutable_telemetry()->set_battery_v(24);
        c.sendEnvelope(e);
      });
  run("not protobuf (16 x 0xff) after the Hello",
      {"closed: malformed frame: 16 bytes do not parse as inspect.v1.Envelope"}, [&](AttackConn& c, Attack& a) {
        if (evilRobot(c, a)) c.sendTls(varint(16) + std::string(16, '\xff'));
      });
  run("a Command from a robot", {"closed: protocol error: robot sent a Command"}, [&](AttackConn& c, Attack& a) {
    if (!evilRobot(c, a)) return;
    v1::Envelope e;
    e.mutable_command()->set_id(1);
    e.mutable_command()->mutable_estop();
    c.sendEnvelope(e);
  });
  run("a second Hello", {"closed: protocol error: second Hello"}, [&](AttackConn& c, Attack& a) {
    if (!evilRobot(c, a)) return;
    v1::Envelope e;
    e.mutable_hello()->set_robot_id("evil999");
    e.mutable_hello()->set_protocol_version(net::kProtocolVersion);
    c.sendEnvelope(e);
  });
  run("random bytes inside TLS after the Hello", kGarbageReasons, [&](AttackConn& c, Attack& a) {
    if (evilRobot(c, a)) c.sendTls(randomBytes(rng, 4096));
  });
  // Corrupt records break the session both ways: which of the server's
  // reads or its next heartbeat write fails first is the scheduler's choice.
  run("random bytes under TLS (corrupt records) after the Hello", {"closed: read error", "closed: write error"},
      [&](AttackConn& c, Attack& a) {
        if (evilRobot(c, a)) c.sendRaw(randomBytes(rng, 512));
      });
  run("Hello as good001 with another robot's certificate",
      {"handshake rejected: robot id 'good001' does not match its certificate"}, [&](AttackConn& c, Attack& a) {
        if (!evilRobot(c, a, false)) return;
        if (c.hello("good001")) a.note = "the server accepted good001 with evil's certificate";
      });

  slow_thread.join();
  const auto mem_slow = sampleProc(server_.pid());

  // ---- flood: an authenticated robot sends telemetry as fast as the link takes it for 3 s ----
  IoThread flood_io;
  FleetRobotOptions fo;
  fo.id = "flood001";
  fo.certs_dir = certs_;
  fo.port = server_.port();
  fo.telemetry_hz = 0;
  auto flood = std::make_shared<FleetRobot>(flood_io.ioc, fo);
  flood->start();
  ASSERT_TRUE(test::waitUntil([&] { return flood->stats().accepted || flood->stats().closed; }, 10.0));
  ASSERT_TRUE(flood->stats().accepted) << flood->closeReason();
  // Its telemetry is recorded too: the recorder is shared by every robot's session.
  ASSERT_TRUE(server_.recordStart({"flood001"}, "flood", 10.0)) << server_.out();
  const auto cpu_f0 = sampleProc(server_.pid());
  const auto tf0 = Clock::now();
  const auto tf0_wall = std::chrono::system_clock::now();
  flood->flood(std::chrono::milliseconds(3000));
  uint64_t flood_peak_rss_kb = 0;
  while (Clock::now() - tf0 < std::chrono::milliseconds(3300)) {
    test::sleepS(0.1);
    flood_peak_rss_kb = std::max(flood_peak_rss_kb, sampleProc(server_.pid()).rss_kb);
  }
  const auto cpu_f1 = sampleProc(server_.pid());
  const double flood_s = std::chrono::duration<double>(Clock::now() - tf0).count();
  const uint64_t flood_sent = flood->stats().telemetry_sent;
  const bool flood_closed_by_server = flood->stats().closed;
  const std::string flood_close_reason = flood->closeReason();
  flood->close();
  test::sleepS(0.3);

  // ---- afterwards the server still takes a new robot ----
  FleetRobotOptions lo = fo;
  lo.id = "late001";
  auto late = std::make_shared<FleetRobot>(flood_io.ioc, lo);
  late->start();
  const bool late_ok = test::waitUntil([&] { return late->stats().accepted || late->stats().closed; }, 10.0) &&
                       late->stats().accepted;
  test::sleepS(0.5);

  // ---- the good robots: still connected, heartbeats, every telemetry recorded ----
  for (auto& r : good) r->stopTelemetry();
  EXPECT_TRUE(server_.drain(good, "good drain", 10.0)) << "the good robots' last messages were not processed";
  test::waitUntil(
      [&] {
        const std::string log = server_.log();
        return std::all_of(attacks.begin(), attacks.end(),
                           [&](const Attack& a) { return !logLineFor(log, a.local, a.expect).empty(); });
      },
      3.0);
  const std::string log_before_quit = server_.log();
  const auto mem_end = sampleProc(server_.pid());
  EXPECT_TRUE(server_.running()) << "pc_server died";
  for (const auto& r : good) {
    EXPECT_FALSE(r->stats().closed) << r->id() << ": " << r->closeReason();
    EXPECT_EQ(logLineFor(log_before_quit, r->id() + " (127.0.0.1", {"closed:"}), "")
        << r->id() << "'s session was closed";
  }
  std::vector<std::string> recorded_ids = good_ids_;
  recorded_ids.push_back("flood001");
  ASSERT_TRUE(server_.recordStop(recorded_ids, 10.0)) << server_.out();
  late->close();
  for (auto& r : good) r->close();
  test::sleepS(0.2);
  good_io.stop();
  flood_io.stop();
  const auto status = server_.quit(15.0);
  EXPECT_EQ(status, std::optional<int>(0)) << "pc_server's exit status (console:\n" << server_.out() << ")";

  std::printf("\n%-72s %-22s %8s  %s\n", "attack", "connection", "closed", "server log");
  for (const auto& a : attacks) {
    const std::string line = logLineFor(log_before_quit, a.local, a.expect);
    char closed[32];
    if (a.attacker_closes) std::snprintf(closed, sizeof closed, "%8s", "itself");
    else if (a.closed_after) std::snprintf(closed, sizeof closed, "%7.2fs", *a.closed_after);
    else std::snprintf(closed, sizeof closed, "%8s", "no");
    std::printf("%-72s %-22s %s  %s\n", a.name.c_str(), a.local.c_str(), closed,
                line.empty() ? "(no line)" : line.substr(line.find('[')).c_str());
    EXPECT_EQ(a.note, "") << a.name;
    if (!a.attacker_closes) {
      EXPECT_TRUE(a.closed_after.has_value()) << a.name << ": the server did not close the connection within 4 s";
    }
    EXPECT_NE(line, "") << a.name << " (" << a.local << "): no log line with one of the expected reasons";
  }

  // Slow connections: each dropped by the handshake timeout, with its reason in the log.
  int slow_ok = 0;
  double slow_min = 1e9, slow_max = 0;
  for (const auto& a : slow) {
    const std::string line = logLineFor(log_before_quit, a.local, a.expect);
    const bool ok = a.note.empty() && a.closed_after && *a.closed_after >= kHandshakeTimeout - 0.05 &&
                    *a.closed_after <= kHandshakeTimeout + 1.5 && !line.empty();
    if (a.closed_after) {
      slow_min = std::min(slow_min, *a.closed_after);
      slow_max = std::max(slow_max, *a.closed_after);
    }
    slow_ok += ok;
    EXPECT_TRUE(ok) << a.name << " (" << a.local << "): note '" << a.note << "', closed after "
                    << a.closed_after.value_or(-1) << " s, log line '" << line << "'";
  }
  std::printf("slow connections: %d of %zu dropped by the %.0f s handshake timeout after %.2f-%.2f s, each logged\n",
              slow_ok, slow.size(), kHandshakeTimeout, slow_min, slow_max);

  std::printf("flood: %llu telemetry messages in %.1f s (%.0f /s), server CPU %.0f %% of a core, peak RSS %.1f MB, "
              "closed by the server: %s\n",
              static_cast<unsigned long long>(flood_sent), 3.0, flood_sent / 3.0,
              100.0 * static_cast<double>(cpu_f1.cpu_ticks - cpu_f0.cpu_ticks) / clockTicksPerSecond() / flood_s,
              flood_peak_rss_kb / 1024.0, flood_closed_by_server ? flood_close_reason.c_str() : "no");
  std::printf("server RSS: %.1f MB before the attacks, %.1f MB after the slow/malformed ones, %.1f MB at the end "
              "(VmHWM %.1f MB)\n",
              mem0.rss_kb / 1024.0, mem_slow.rss_kb / 1024.0, mem_end.rss_kb / 1024.0, mem_end.hwm_kb / 1024.0);
  EXPECT_GT(flood_sent, 3000u) << "the flood did not flood";
  {
    // Throttled within 1 s of the flood's start (the log line's time), then
    // closed as it kept on for robot_limits.close_after_s (2 s here); what
    // was recorded of it is bounded by the limit (2000 messages/s, 1 s burst).
    const std::string throttled = logLineFor(log_before_quit, "flood001 (127.0.0.1", {"throttled: over 2000 messages/s"});
    const std::string closed = logLineFor(log_before_quit, "flood001 (127.0.0.1", {"closed: flooding: over the limits"});
    const auto start_t = std::chrono::system_clock::to_time_t(tf0_wall);
    std::tm tm{};
    localtime_r(&start_t, &tm);
    const int64_t start_ms = ((tm.tm_hour * 60 + tm.tm_min) * 60 + tm.tm_sec) * 1000LL +
                             std::chrono::duration_cast<std::chrono::milliseconds>(tf0_wall.time_since_epoch()).count() % 1000;
    const auto msOf = [](const std::string& l) {
      return ((std::stoll(l.substr(0, 2)) * 60 + std::stoll(l.substr(3, 2))) * 60 + std::stoll(l.substr(6, 2))) * 1000 +
             std::stoll(l.substr(9, 3));
    };
    ASSERT_FALSE(throttled.empty()) << "the flooding robot was not throttled";
    ASSERT_FALSE(closed.empty()) << "the flooding robot's session was not closed";
    const int64_t throttled_after_ms = (msOf(throttled) - start_ms + 86'400'000) % 86'400'000;
    const int64_t closed_after_ms = (msOf(closed) - start_ms + 86'400'000) % 86'400'000;
    const auto rec = readTelemetry(server_.mcapPath("flood001"));
    std::printf("flood001: telemetry sent %llu, recorded %zu; throttled %lld ms after the flood began, closed after "
                "%lld ms\n",
                static_cast<unsigned long long>(flood_sent), rec.size(), static_cast<long long>(throttled_after_ms),
                static_cast<long long>(closed_after_ms));
    EXPECT_LE(throttled_after_ms, 1000) << throttled;
    EXPECT_GE(closed_after_ms, 2000) << closed;
    EXPECT_LE(rec.size(), static_cast<std::size_t>(2000 * (closed_after_ms / 1000.0 + 1.0) + 100));
    EXPECT_TRUE(flood_closed_by_server) << "the flooding robot's session was not closed";
  }
  EXPECT_TRUE(late_ok) << "a new robot could not connect after the attacks: " << late->closeReason();
  EXPECT_LT(mem_end.hwm_kb, 512u * 1024u) << "server memory peaked above 512 MB";
  {
    // No error-level line (a failed recording write, a serialisation failure, ...).
    std::istringstream in(log_before_quit);
    for (std::string line; std::getline(in, line);)
      EXPECT_EQ(line.find(" E ["), std::string::npos) << "error in the server log: " << line;
  }

  // Every telemetry message of the good robots recorded, by sequence number.
  for (const auto& r : good) {
    const auto rec = readTelemetry(server_.mcapPath(r->id()));
    const auto c = checkSequence(rec, r->stats().telemetry_sent);
    int64_t worst_ms = 0;
    const int64_t offset = wallMinusMonoNs();
    for (const auto& m : rec)
      worst_ms = std::max<int64_t>(worst_ms, ((static_cast<int64_t>(m.log_time_ns) - offset) / 1000 -
                                              static_cast<int64_t>(m.send_us)) / 1000);
    std::printf("%s: telemetry sent %llu, recorded %llu, missing %llu (first %llu), duplicates %llu; heartbeats "
                "received %llu, longest gap %.0f ms; worst telemetry latency %lld ms\n",
                r->id().c_str(), static_cast<unsigned long long>(c.sent), static_cast<unsigned long long>(c.recorded),
                static_cast<unsigned long long>(c.missing), static_cast<unsigned long long>(c.first_missing),
                static_cast<unsigned long long>(c.duplicates),
                static_cast<unsigned long long>(r->stats().heartbeats_received.load()),
                r->stats().max_heartbeat_gap_us / 1000.0, static_cast<long long>(worst_ms));
    EXPECT_GT(c.sent, 500u) << r->id();
    EXPECT_EQ(c.missing, 0u) << r->id() << ": first missing sequence number " << c.first_missing;
    EXPECT_EQ(c.duplicates, 0u) << r->id();
    EXPECT_EQ(c.unexpected, 0u) << r->id();
    EXPECT_EQ(c.recorded, c.sent) << r->id();
    // robot_client stops on its own after 0.3 s without a message from the server.
    EXPECT_LT(r->stats().max_heartbeat_gap_us, 300'000) << r->id() << ": server heartbeats stalled";
    // 10 Hz of heartbeats over the whole scenario (telemetry started 1 s after the Hello).
    EXPECT_GE(r->stats().heartbeats_received, c.sent / 10) << r->id();
  }
  const double total_s = std::chrono::duration<double>(Clock::now() - t_start).count();
  std::printf("whole scenario: %.1f s\n", total_s);
  EXPECT_LT(total_s, 60.0);
}

}  // namespace
}  // namespace inspect::linktest
