// link_load: load generator for the robot <-> server link (docs/load.md).
//
// For each fleet size N it starts one real pc_server (mutual TLS, recording
// on into a temporary runs directory, no video), connects N simulated robots
// (tests/support/fake_robot/fleet_robot.hpp: Hello, heartbeats every 100 ms, telemetry at
// --hz with realistic content and sequence numbers, an Ack for every
// command, each robot with its own certificate), starts a recorded run for
// every robot from the console, and measures over --seconds:
//   - server CPU (utime + stime from /proc/<pid>/stat) and RSS (VmRSS sampled,
//     VmHWM), the generator's own CPU;
//   - telemetry latency: Envelope.send_time_us (the generator's CLOCK_MONOTONIC)
//     to the server's receive time, which the MCAP recording keeps as each
//     message's log_time (the receive time on CLOCK_MONOTONIC as wall-clock ns:
//     this machine's CLOCK_REALTIME - CLOCK_MONOTONIC is subtracted again);
//   - drops: every telemetry sequence number sent must be in the recording
//     exactly once;
//   - bytes/s (protobuf frames, and bytes written to the TLS sockets).
// Prints a table and, with --json FILE, writes the figures. Exit status 0 when
// nothing was lost and every robot stayed connected, 1 otherwise, 2 for a bad
// command line.
#include <sys/resource.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>

#include "shared/util/cli_args.hpp"
#include "shared/util/clock.hpp"
#include "tests/support/mosquitto_broker.hpp"
#include "tests/support/paths.hpp"
#include "tests/support/process.hpp"
#include "tests/support/sparkplug_host.hpp"
#include "tests/system/link/server_harness.hpp"
#include "tests/support/fake_robot/fleet_robot.hpp"
#include "tests/support/test_certs.hpp"

namespace {

namespace asio = boost::asio;
using namespace inspect;
using namespace inspect::linktest;
using inspect::test::FleetRobot;
using inspect::test::FleetRobotOptions;
using inspect::test::robotId;
using Clock = std::chrono::steady_clock;

struct Options {
  std::vector<int> robots = {1, 10, 25, 50};
  double seconds = 20.0;
  double warmup_s = 2.0;
  double idle_s = 2.0;
  double hz = 100.0;
  int threads = 1;
  bool commands = true;  // one `stop` per robot through the console (acked)
  std::string json;
  std::string config;  // pc_server --config ("" = config/server.yaml)
  bool mqtt = false;   // the server a Sparkplug edge node on a mosquitto of its own, read by the Python host
  double alarm_period_s = 2.0;  // --mqtt: each robot raises or clears an alarm this often
};

void usage(std::ostream& o) {
  o << "link_load [--robots 1,10,25,50] [--seconds 20] [--warmup 2] [--idle 2] [--hz 100] [--threads 1]\n"
       "          [--no-commands] [--config FILE] [--mqtt [--alarm-period S]] [--json FILE]\n"
       "  For each fleet size: one real pc_server (TLS, recording on), N simulated robots at --hz telemetry.\n"
       "  --robots   fleet sizes, comma separated (1-500 each)\n"
       "  --seconds  measurement window per fleet size (after --warmup seconds of telemetry)\n"
       "  --idle     server measured idle this long before the robots connect (its baseline)\n"
       "  --threads  generator io threads (robots spread over them)\n"
       "  --no-commands  no console `stop` to each robot (by default each robot gets one and acks it)\n"
       "  --mqtt     pc_server also a Sparkplug B edge node (docs/sparkplug.md) on a mosquitto of its own,\n"
       "             read by the Python Sparkplug host (tests/tools/sparkplug_host.py); each robot raises and\n"
       "             clears a gas alarm every --alarm-period S (2): every transition must reach the host once\n"
       "  --json     write every figure to FILE\n"
       "  Exit status: 0 = no telemetry lost and every robot stayed connected; 1 = not; 2 = bad arguments.\n"
       "  KEEP_TEST_DIRS=1 keeps the server's directories (logs, runs) under $TMPDIR.\n";
}

void parse(int argc, char** argv, Options& o) {
  cli::readOrExit("link_load", argc, argv, [&](cli::ArgReader& a) {
    if (a.is("--robots")) {
      o.robots.clear();
      for (const auto& item : a.list()) {
        char* end = nullptr;
        const long n = std::strtol(item.c_str(), &end, 10);
        if (*end || n < 1 || n > 500) a.fail("'" + item + "' is not a whole number in [1, 500]");
        o.robots.push_back(static_cast<int>(n));
      }
    } else if (a.is("--seconds")) {
      o.seconds = a.number(1, 3600);
    } else if (a.is("--warmup")) {
      o.warmup_s = a.number(0, 60);
    } else if (a.is("--idle")) {
      o.idle_s = a.number(0.5, 60);
    } else if (a.is("--hz")) {
      o.hz = a.number(1, 1000);
    } else if (a.is("--threads")) {
      o.threads = static_cast<int>(a.integer(1, 16));
    } else if (a.is("--no-commands")) {
      o.commands = false;
    } else if (a.is("--json")) {
      o.json = a.path();
    } else if (a.is("--config")) {
      o.config = a.path();
    } else if (a.is("--mqtt")) {
      o.mqtt = true;
    } else if (a.is("--alarm-period")) {
      o.alarm_period_s = a.number(0.25, 600);
    } else if (a.isHelp()) {
      usage(std::cout);
      std::exit(0);
    } else {
      a.unknown();
    }
  });
}

double cpuSecondsSelf() {
  rusage u{};
  ::getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double percentile(std::vector<int64_t>& v, double p) {
  if (v.empty()) return NAN;
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(std::ceil(p * static_cast<double>(v.size())) - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return static_cast<double>(v[k]);
}

double loadAverage() {
  double l[3] = {0, 0, 0};
  return ::getloadavg(l, 3) > 0 ? l[0] : NAN;
}

struct Result {
  int robots = 0;
  bool ok = false;
  std::string error;
  double window_s = 0;
  double server_cpu_idle_pct = 0, server_cpu_pct = 0, gen_cpu_pct = 0;
  double rss_idle_mb = 0, rss_end_mb = 0, rss_peak_mb = 0, hwm_mb = 0;
  uint64_t server_threads = 0;
  double lat_p50_ms = NAN, lat_p99_ms = NAN, lat_max_ms = NAN, lat_min_ms = NAN;
  uint64_t lat_samples = 0;
  uint64_t sent = 0, recorded = 0, missing = 0, duplicates = 0, out_of_order = 0;
  double tlm_hz_per_robot = 0;
  double app_bytes_per_s = 0, wire_bytes_per_s = 0, wire_down_bytes_per_s = 0, mcap_bytes = 0, mcap_bytes_per_s = 0;
  double mcap_bytes_per_msg = 0;
  double msg_bytes = 0;  // mean telemetry frame
  double hb_rx_hz_per_robot = 0, max_hb_gap_ms = 0;
  uint64_t commands = 0, acks = 0, robots_closed = 0;
  double clock_offset_drift_us = 0;
  double drain_s = 0;  // from the end of telemetry until the server had processed all of it
  double load_avg = NAN;
  std::vector<nlohmann::json> per_robot;
  // --mqtt: the Sparkplug host's view of the alarm transitions.
  bool mqtt = false;
  uint64_t alarms_sent = 0, alarms_at_host = 0, alarms_missing = 0, alarms_duplicated = 0, host_messages = 0;
  uint64_t host_violations = 0, alarms_historical = 0;
  double alarm_p50_ms = NAN, alarm_p99_ms = NAN, alarm_max_ms = NAN;
  double sparkplug_thread_cpu_pct = 0;  // the edge node's own thread, of one core
};

Result runOne(const Options& opt, int n) {
  Result r;
  r.robots = n;
  test::TempDir dir("link_load_" + std::to_string(n));
  std::vector<std::string> ids;
  for (int i = 1; i <= n; ++i) ids.push_back(robotId("load", i));
  std::string certs;
  try {
    certs = test::testCertsDir(ids);
  } catch (const std::exception& e) {
    r.error = e.what();
    return r;
  }

  // --mqtt: a broker of its own, the Python Sparkplug host as the primary host, the server's config pointed at them.
  std::unique_ptr<test::MosquittoBroker> broker;
  test::Process host;
  std::string config = opt.config;
  const std::string host_json = test::sparkplugHostJson(dir.path());
  if (opt.mqtt) {
    r.mqtt = true;
    try {
      broker = std::make_unique<test::MosquittoBroker>(dir.path());
      config = dir / "server.yaml";
      test::writeFile(config, test::sparkplugServerConfig(
                                  opt.config.empty() ? test::srcPath("config/server.yaml") : opt.config, *broker, "loadhost"));
      host = test::startSparkplugHost(*broker, dir.path(), "loadhost", {"--seconds", "3600", "--until-ndeath"});
    } catch (const std::exception& e) {
      r.error = e.what();
      return r;
    }
  }

  ServerUnderTest server;
  if (!server.start({dir.path(), certs, config, {}})) {
    r.error = "pc_server did not start: " + server.error();
    return r;
  }
  const double tck = clockTicksPerSecond();

  // Idle baseline: the server with no robot.
  test::sleepS(0.5);
  const auto idle0 = sampleProc(server.pid());
  const auto ti0 = Clock::now();
  test::sleepS(opt.idle_s);
  const auto idle1 = sampleProc(server.pid());
  const double idle_wall = std::chrono::duration<double>(Clock::now() - ti0).count();
  r.server_cpu_idle_pct = 100.0 * static_cast<double>(idle1.cpu_ticks - idle0.cpu_ticks) / tck / idle_wall;
  r.rss_idle_mb = static_cast<double>(idle1.rss_kb) / 1024.0;

  // The generator: robots spread over io_contexts with a thread each.
  std::vector<std::unique_ptr<asio::io_context>> iocs;
  std::vector<asio::executor_work_guard<asio::io_context::executor_type>> guards;
  std::vector<std::thread> threads;
  for (int t = 0; t < opt.threads; ++t) {
    iocs.push_back(std::make_unique<asio::io_context>(1));
    guards.push_back(asio::make_work_guard(*iocs.back()));
  }
  for (auto& ioc : iocs) threads.emplace_back([&ioc] { ioc->run(); });
  auto stopGenerator = [&] {
    for (auto& g : guards) g.reset();
    for (auto& ioc : iocs) ioc->stop();
    for (auto& t : threads)
      if (t.joinable()) t.join();
  };

  std::vector<std::shared_ptr<FleetRobot>> robots;
  auto fail = [&](const std::string& why) {
    r.error = why;
    for (auto& rb : robots) rb->close();
    test::sleepS(0.2);
    stopGenerator();
    const auto st = server.quit(10.0);
    r.error += st ? " (pc_server exit status " + std::to_string(*st) + ")" : " (pc_server killed after 10 s)";
    return r;
  };
  try {
    for (int i = 0; i < n; ++i) {
      FleetRobotOptions so;
      so.id = ids[i];
      so.certs_dir = certs;
      so.port = server.port();
      so.telemetry_hz = opt.hz;
      so.seed = static_cast<uint32_t>(1000 + i);
      robots.push_back(std::make_shared<FleetRobot>(*iocs[static_cast<std::size_t>(i % opt.threads)], so));
      robots.back()->start();
    }
  } catch (const std::exception& e) {
    return fail(std::string("robot start: ") + e.what());
  }
  const bool all_up = test::waitUntil(
      [&] {
        return std::all_of(robots.begin(), robots.end(),
                           [](const auto& rb) { return rb->stats().accepted || rb->stats().closed; });
      },
      30.0);
  for (const auto& rb : robots)
    if (!rb->stats().accepted)
      return fail(rb->id() + " not accepted" + (all_up ? ": " + rb->closeReason() : " within 30 s"));

  if (!server.recordStart(ids, "link_load", 30.0)) return fail("record start not confirmed within 30 s");
  // One command per robot through the console (acked by the robot, recorded in its run).
  for (const auto& id : ids) {
    if (!opt.commands) break;
    server.console("select " + id);
    server.console("stop");
  }
  if (opt.commands) test::waitUntil(
      [&] {
        return std::all_of(robots.begin(), robots.end(), [](const auto& rb) { return rb->stats().acks_sent >= 1; });
      },
      10.0 + 0.2 * n);

  for (auto& rb : robots) rb->startTelemetry();
  test::sleepS(opt.warmup_s);
  for (auto& rb : robots) rb->resetHeartbeatGap();

  // The measurement window.
  std::vector<uint64_t> sent0, hb0;
  uint64_t app0 = 0, wire_up0 = 0, wire_down0 = 0;
  for (const auto& rb : robots) {
    const auto tb = rb->tcpBytes();
    wire_up0 += tb.sent_acked;
    wire_down0 += tb.received;
    sent0.push_back(rb->stats().telemetry_sent);
    hb0.push_back(rb->stats().heartbeats_received);
    app0 += rb->stats().app_bytes_sent;
  }
  const int64_t offset0 = wallMinusMonoNs();
  const uint64_t t0_us = monoNowUs();
  const auto w0 = Clock::now();
  const auto s0 = sampleProc(server.pid());
  const double spark0 = opt.mqtt ? test::threadCpuTicks(server.pid())["sparkplug"] : 0;
  const double gcpu0 = cpuSecondsSelf();
  uint64_t peak_rss_kb = s0.rss_kb;
  // --mqtt: each robot raises or clears its alarm every alarm_period_s, the fleet spread over the period.
  const int alarm_ticks = std::max(1, static_cast<int>(std::lround(opt.alarm_period_s / 0.25)));
  int tick = 0;
  while (Clock::now() - w0 < std::chrono::duration<double>(opt.seconds)) {
    test::sleepS(0.25);
    for (std::size_t i = 0; opt.mqtt && i < robots.size(); ++i)
      if ((tick + static_cast<int>(i)) % alarm_ticks == 0) robots[i]->sendAlarmTransition();
    ++tick;
    const auto s = sampleProc(server.pid());
    if (!s.ok) break;  // the server died: reported below
    peak_rss_kb = std::max(peak_rss_kb, s.rss_kb);
  }
  const auto s1 = sampleProc(server.pid());
  const double spark1 = opt.mqtt ? test::threadCpuTicks(server.pid())["sparkplug"] : 0;
  const double gcpu1 = cpuSecondsSelf();
  const uint64_t t1_us = monoNowUs();
  r.window_s = std::chrono::duration<double>(Clock::now() - w0).count();
  const int64_t offset1 = wallMinusMonoNs();
  r.load_avg = loadAverage();
  if (!s1.ok) return fail("pc_server is gone during the measurement:\n" + server.log());
  uint64_t app1 = 0, sent_window = 0, hb_window = 0, wire_up1 = 0, wire_down1 = 0;
  for (std::size_t i = 0; i < robots.size(); ++i) {
    const auto tb = robots[i]->tcpBytes();
    wire_up1 += tb.sent_acked;
    wire_down1 += tb.received;
    app1 += robots[i]->stats().app_bytes_sent;
    sent_window += robots[i]->stats().telemetry_sent - sent0[i];
    hb_window += robots[i]->stats().heartbeats_received - hb0[i];
  }
  r.server_cpu_pct = 100.0 * static_cast<double>(s1.cpu_ticks - s0.cpu_ticks) / tck / r.window_s;
  r.gen_cpu_pct = 100.0 * (gcpu1 - gcpu0) / r.window_s;
  r.sparkplug_thread_cpu_pct = 100.0 * (spark1 - spark0) / tck / r.window_s;
  r.rss_end_mb = static_cast<double>(s1.rss_kb) / 1024.0;
  r.rss_peak_mb = static_cast<double>(std::max(peak_rss_kb, s1.rss_kb)) / 1024.0;
  r.hwm_mb = static_cast<double>(s1.hwm_kb) / 1024.0;
  r.server_threads = s1.threads;
  r.app_bytes_per_s = static_cast<double>(app1 - app0) / r.window_s;
  r.wire_bytes_per_s = static_cast<double>(wire_up1 - wire_up0) / r.window_s;
  r.wire_down_bytes_per_s = static_cast<double>(wire_down1 - wire_down0) / r.window_s;
  r.tlm_hz_per_robot = static_cast<double>(sent_window) / r.window_s / n;
  r.hb_rx_hz_per_robot = static_cast<double>(hb_window) / r.window_s / n;
  r.clock_offset_drift_us = static_cast<double>(offset1 - offset0) / 1000.0;

  // Drain (every robot's last message processed by the server), end the runs, disconnect.
  for (auto& rb : robots) rb->stopTelemetry();
  const auto td0 = Clock::now();
  const bool drained = server.drain(robots, "link_load drain", 60.0);
  r.drain_s = std::chrono::duration<double>(Clock::now() - td0).count();
  int64_t max_gap_us = 0;
  for (const auto& rb : robots) {
    max_gap_us = std::max<int64_t>(max_gap_us, rb->stats().max_heartbeat_gap_us);
    r.commands += rb->stats().commands_received;
    r.acks += rb->stats().acks_sent;
    r.robots_closed += rb->stats().closed ? 1 : 0;
  }
  r.max_hb_gap_ms = static_cast<double>(max_gap_us) / 1000.0;
  const bool stopped = server.recordStop(ids, 30.0);
  if (!drained) r.error = "the server did not process the robots' drain markers within 60 s; ";
  for (auto& rb : robots) rb->close();
  test::sleepS(0.3);
  stopGenerator();
  const auto exit_status = server.quit(15.0);
  if (opt.mqtt) {
    for (const auto& rb : robots) r.alarms_sent += rb->stats().alarm_transitions_sent;
    // The server's clean stop publishes NDEATH; the host ends with it.
    if (!host.wait(20.0)) {
      r.error += "the Sparkplug host saw no NDEATH within 20 s; ";
      host.terminate();
    }
    try {
      const auto h = nlohmann::json::parse(test::readFile(host_json));
      r.host_messages = h["messages"].get<uint64_t>();
      r.host_violations = h["violations"].size();
      std::map<std::pair<std::string, std::pair<uint64_t, bool>>, int> seen;
      std::vector<int64_t> lat_ms;
      for (const auto& a : h["alarms"]) {
        ++seen[{a["device"].get<std::string>(), {a["id"].get<uint64_t>(), a["active"].get<bool>()}}];
        if (a["historical"].get<bool>()) {
          ++r.alarms_historical;
          continue;
        }
        lat_ms.push_back(a["received_ms"].get<int64_t>() - a["timestamp_ms"].get<int64_t>());
      }
      r.alarms_at_host = h["alarms"].size();
      for (const auto& [k, count] : seen) r.alarms_duplicated += static_cast<uint64_t>(count - 1);
      const uint64_t distinct = seen.size();
      r.alarms_missing = r.alarms_sent > distinct ? r.alarms_sent - distinct : 0;
      if (!lat_ms.empty()) {
        r.alarm_max_ms = static_cast<double>(*std::max_element(lat_ms.begin(), lat_ms.end()));
        r.alarm_p50_ms = percentile(lat_ms, 0.50);
        r.alarm_p99_ms = percentile(lat_ms, 0.99);
      }
      if (r.host_violations) r.error += h["violations"][0].get<std::string>() + "; ";
    } catch (const std::exception& e) {
      r.error += std::string("the Sparkplug host's JSON: ") + e.what() + "; ";
    }
  }
  if (!stopped) {
    r.error += "record stop not confirmed within 30 s";
    return r;
  }

  // Read the recordings back.
  std::vector<int64_t> lat_us;
  const int64_t offset = (offset0 + offset1) / 2;
  for (std::size_t i = 0; i < robots.size(); ++i) {
    const auto& rb = robots[i];
    const std::string path = server.mcapPath(rb->id());
    std::vector<RecordedTelemetry> rec;
    try {
      rec = readTelemetry(path);
    } catch (const std::exception& e) {
      r.error = rb->id() + ": " + e.what();
      return r;
    }
    const auto c = checkSequence(rec, rb->stats().telemetry_sent);
    r.sent += c.sent;
    r.recorded += c.recorded;
    r.missing += c.missing;
    r.duplicates += c.duplicates;
    r.out_of_order += c.out_of_order;
    for (const auto& m : rec) {
      if (m.send_us < t0_us || m.send_us > t1_us) continue;
      const int64_t recv_us = (static_cast<int64_t>(m.log_time_ns) - offset) / 1000;
      lat_us.push_back(recv_us - static_cast<int64_t>(m.send_us));
    }
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (!ec) r.mcap_bytes += static_cast<double>(size);
    nlohmann::json pr;
    pr["id"] = rb->id();
    pr["sent"] = c.sent;
    pr["recorded"] = c.recorded;
    pr["missing"] = c.missing;
    pr["duplicates"] = c.duplicates;
    pr["out_of_order"] = c.out_of_order;
    pr["first_missing"] = c.first_missing;
    pr["heartbeats_received"] = rb->stats().heartbeats_received.load();
    pr["max_heartbeat_gap_ms"] = static_cast<double>(rb->stats().max_heartbeat_gap_us) / 1000.0;
    pr["closed"] = rb->stats().closed.load();
    pr["close_reason"] = rb->closeReason();
    r.per_robot.push_back(pr);
  }
  // Mean frame: the window's protobuf bytes (telemetry, and a few heartbeats) per telemetry message.
  r.msg_bytes = sent_window ? static_cast<double>(app1 - app0) / static_cast<double>(sent_window) : 0;
  // The runs also hold a little before and after the telemetry: MCAP bytes per telemetry
  // message, times the window's telemetry rate.
  r.mcap_bytes_per_msg = r.sent ? r.mcap_bytes / static_cast<double>(r.sent) : 0;
  r.mcap_bytes_per_s = r.mcap_bytes_per_msg * static_cast<double>(sent_window) / r.window_s;
  r.lat_samples = lat_us.size();
  if (!lat_us.empty()) {
    r.lat_min_ms = static_cast<double>(*std::min_element(lat_us.begin(), lat_us.end())) / 1000.0;
    r.lat_max_ms = static_cast<double>(*std::max_element(lat_us.begin(), lat_us.end())) / 1000.0;
    r.lat_p50_ms = percentile(lat_us, 0.50) / 1000.0;
    r.lat_p99_ms = percentile(lat_us, 0.99) / 1000.0;
  }
  // robots_closed counts links that ended before we closed them ourselves.
  r.ok = drained && r.missing == 0 && r.duplicates == 0 && r.robots_closed == 0 &&
         (!opt.mqtt || (r.alarms_missing == 0 && r.alarms_duplicated == 0 && r.host_violations == 0 && r.alarms_sent > 0)) &&
         (!opt.commands || r.acks >= static_cast<uint64_t>(n)) && exit_status.has_value();
  if (!r.ok) {
    std::ostringstream e;
    e << r.error << "missing " << r.missing << ", duplicates " << r.duplicates << ", robots closed early " << r.robots_closed
      << ", acks " << r.acks << "/" << n << (exit_status ? "" : ", pc_server did not quit within 15 s");
    if (opt.mqtt)
      e << ", alarm transitions sent " << r.alarms_sent << " at the host " << r.alarms_at_host << " missing "
        << r.alarms_missing << " twice " << r.alarms_duplicated << ", Sparkplug violations " << r.host_violations;
    r.error = e.str();
  }
  return r;
}

void printTable(const std::vector<Result>& rs, const Options& o) {
  std::printf("\nlink_load: %.0f Hz telemetry per robot, %.0f s window (after %.0f s warm-up), TLS, recording on, "
              "%d generator thread(s), %ld cores\n",
              o.hz, o.seconds, o.warmup_s, o.threads, ::sysconf(_SC_NPROCESSORS_ONLN));
  std::printf("%6s %8s %8s %8s %8s %7s %7s %7s %7s %7s %7s %7s %9s %9s %7s %8s %8s %8s %6s %6s\n", "robots",
              "srv CPU%", "CPU%/rob", "idle CPU", "gen CPU%", "RSS MB", "peak MB", "MB/rob", "p50 ms", "p99 ms",
              "max ms", "tlm Hz", "tlm sent", "recorded", "dropped", "pb kB/s", "tcp kB/s", "mcap kB/s", "hb gap",
              "closed");
  for (const auto& r : rs) {
    if (!r.error.empty() && r.sent == 0) {
      std::printf("%6d  FAILED: %s\n", r.robots, r.error.c_str());
      continue;
    }
    const double cpu_per = (r.server_cpu_pct - r.server_cpu_idle_pct) / r.robots;
    const double mb_per = (r.rss_end_mb - r.rss_idle_mb) / r.robots;
    std::printf("%6d %8.1f %8.2f %8.1f %8.1f %7.1f %7.1f %7.2f %7.2f %7.2f %7.2f %7.1f %9llu %9llu %7llu %8.1f %8.1f "
                "%8.1f %6.0f %6llu\n",
                r.robots, r.server_cpu_pct, cpu_per, r.server_cpu_idle_pct, r.gen_cpu_pct, r.rss_end_mb, r.hwm_mb,
                mb_per, r.lat_p50_ms, r.lat_p99_ms, r.lat_max_ms, r.tlm_hz_per_robot,
                static_cast<unsigned long long>(r.sent), static_cast<unsigned long long>(r.recorded),
                static_cast<unsigned long long>(r.missing + r.duplicates), r.app_bytes_per_s / 1000.0,
                r.wire_bytes_per_s / 1000.0, r.mcap_bytes_per_s / 1000.0, r.max_hb_gap_ms,
                static_cast<unsigned long long>(r.robots_closed));
    if (!r.error.empty()) std::printf("       ^ %s\n", r.error.c_str());
  }
  if (rs.size() >= 2 && rs.front().sent > 0 && rs.back().sent > 0) {
    const auto& a = rs.front();
    const auto& b = rs.back();
    const double dn = b.robots - a.robots;
    if (dn > 0)
      std::printf("growth %d -> %d robots: +%.2f %% of a core and +%.2f MB RSS per added robot; p99 latency %.2f -> "
                  "%.2f ms\n",
                  a.robots, b.robots, (b.server_cpu_pct - a.server_cpu_pct) / dn, (b.rss_end_mb - a.rss_end_mb) / dn,
                  a.lat_p99_ms, b.lat_p99_ms);
  }
  if (o.mqtt) {
    std::printf("\nSparkplug B (--mqtt): every robot raises or clears a CH4 alarm every %.1f s; the Python host "
                "(primary host) counts them\n%6s %9s %9s %9s %8s %8s %8s %8s %8s %8s %9s %10s\n",
                o.alarm_period_s, "robots", "srv CPU%", "edge CPU%", "sent", "at host", "missing", "twice", "p50 ms", "p99 ms",
                "max ms", "host msgs", "violations");
    for (const auto& r : rs)
      std::printf("%6d %9.1f %9.1f %9llu %8llu %8llu %8llu %8.0f %8.0f %8.0f %9llu %10llu\n", r.robots,
                  r.server_cpu_pct, r.sparkplug_thread_cpu_pct,
                  static_cast<unsigned long long>(r.alarms_sent), static_cast<unsigned long long>(r.alarms_at_host),
                  static_cast<unsigned long long>(r.alarms_missing),
                  static_cast<unsigned long long>(r.alarms_duplicated), r.alarm_p50_ms, r.alarm_p99_ms, r.alarm_max_ms,
                  static_cast<unsigned long long>(r.host_messages), static_cast<unsigned long long>(r.host_violations));
    std::printf("edge CPU%% = the server's sparkplug thread alone (the MQTT session, metrics, births and data).\n");
    std::printf("Alarm latency = the robot's time of the transition (its clock, as the server converts it) -> the "
                "host's on_message, wall clock, ms.\n");
  }
  std::printf("CPU%% = of one core (utime+stime over the window); CPU%%/rob and MB/rob = above the idle server. "
              "peak MB = VmHWM.\nLatency = Envelope.send_time_us on the generator -> receive time in the server "
              "(MCAP log_time), all messages of the window.\npb = protobuf frames robot -> server; tcp = TLS bytes "
              "robot -> server (TCP_INFO); mcap = recording written. hb gap = longest gap between server "
              "heartbeats at a robot, ms.\n");
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  parse(argc, argv, opt);
  std::vector<Result> results;
  for (const int n : opt.robots) {
    std::fprintf(stderr, "link_load: %d robot(s): idle %.0f s, warm-up %.0f s, window %.0f s ...\n", n, opt.idle_s,
                 opt.warmup_s, opt.seconds);
    results.push_back(runOne(opt, n));
    const auto& r = results.back();
    std::fprintf(stderr, "link_load: %d robot(s): %s\n", n, r.ok ? "ok" : ("FAILED: " + r.error).c_str());
  }
  printTable(results, opt);
  if (!opt.json.empty()) {
    nlohmann::json j;
    j["hz"] = opt.hz;
    j["seconds"] = opt.seconds;
    j["warmup_s"] = opt.warmup_s;
    j["generator_threads"] = opt.threads;
    j["cores"] = ::sysconf(_SC_NPROCESSORS_ONLN);
    for (const auto& r : results) {
      nlohmann::json e;
      e["robots"] = r.robots;
      e["ok"] = r.ok;
      e["error"] = r.error;
      e["window_s"] = r.window_s;
      e["server_cpu_pct"] = r.server_cpu_pct;
      e["server_cpu_idle_pct"] = r.server_cpu_idle_pct;
      e["server_cpu_pct_per_robot"] = (r.server_cpu_pct - r.server_cpu_idle_pct) / r.robots;
      e["generator_cpu_pct"] = r.gen_cpu_pct;
      e["server_threads"] = r.server_threads;
      e["rss_idle_mb"] = r.rss_idle_mb;
      e["rss_end_mb"] = r.rss_end_mb;
      e["rss_peak_mb"] = r.rss_peak_mb;
      e["vmhwm_mb"] = r.hwm_mb;
      e["rss_mb_per_robot"] = (r.rss_end_mb - r.rss_idle_mb) / r.robots;
      e["latency_ms"] = {{"min", r.lat_min_ms}, {"p50", r.lat_p50_ms}, {"p99", r.lat_p99_ms}, {"max", r.lat_max_ms},
                         {"samples", r.lat_samples}};
      e["telemetry"] = {{"sent", r.sent},           {"recorded", r.recorded},
                        {"missing", r.missing},     {"duplicates", r.duplicates},
                        {"out_of_order", r.out_of_order}, {"hz_per_robot", r.tlm_hz_per_robot},
                        {"mean_frame_bytes", r.msg_bytes}};
      e["bytes_per_s"] = {{"protobuf_up", r.app_bytes_per_s},
                          {"tcp_up", r.wire_bytes_per_s},
                          {"tcp_down", r.wire_down_bytes_per_s},
                          {"mcap", r.mcap_bytes_per_s}};
      e["mcap_bytes_per_telemetry"] = r.mcap_bytes_per_msg;
      e["mcap_bytes"] = r.mcap_bytes;
      e["heartbeats"] = {{"rx_hz_per_robot", r.hb_rx_hz_per_robot}, {"max_gap_ms", r.max_hb_gap_ms}};
      e["commands"] = r.commands;
      e["acks"] = r.acks;
      e["robots_closed_early"] = r.robots_closed;
      e["clock_offset_drift_us"] = r.clock_offset_drift_us;
      e["drain_s"] = r.drain_s;
      e["load_average_1min"] = r.load_avg;
      e["per_robot"] = r.per_robot;
      if (r.mqtt)
        e["sparkplug"] = {{"alarm_period_s", opt.alarm_period_s}, {"thread_cpu_pct", r.sparkplug_thread_cpu_pct},
                          {"transitions_sent", r.alarms_sent},
                          {"at_host", r.alarms_at_host}, {"missing", r.alarms_missing},
                          {"duplicated", r.alarms_duplicated}, {"historical", r.alarms_historical},
                          {"latency_ms", {{"p50", r.alarm_p50_ms}, {"p99", r.alarm_p99_ms}, {"max", r.alarm_max_ms}}},
                          {"host_messages", r.host_messages}, {"violations", r.host_violations}};
      j["runs"].push_back(e);
    }
    std::ofstream f(opt.json);
    f << j.dump(2) << "\n";
    if (!f) {
      std::cerr << "link_load: cannot write " << opt.json << "\n";
      return 1;
    }
  }
  return std::all_of(results.begin(), results.end(), [](const Result& r) { return r.ok; }) ? 0 : 1;
}
