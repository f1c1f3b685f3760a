// bench_foxglove: the Foxglove bridge's delivery latency - a telemetry
// message's arrival at the server (the link's observer call) to its delivery
// to a WebSocket client - with 1 and 10 subscribed clients, and with 10 plus
// one that never reads (docs/foxglove.md, "Back-pressure"). In process: the
// real bridge and its Beast server on 127.0.0.1, real Beast clients on their
// own threads subscribed to every channel, telemetry at 50 Hz and camera
// frames at 30 fps fed as the link and the video receiver feed them.
// Figures: latency p50/p99/max per case and its ratio to the 1-client case,
// telemetry received per client per second, how long the link's call into
// the bridge took (it must never wait for a client), the slow client's drops.
//
//   bench_foxglove [--seconds S] [--json FILE] [--quick]
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include "pc_server/foxglove/foxglove_bridge.hpp"
#include "pc_server/link/robot_registry.hpp"
#include "pc_server/operator/control_arbiter.hpp"
#include "pc_server/scene/site_maps.hpp"
#include "shared/util/cli_args.hpp"
#include "shared/util/clock.hpp"
#include "shared/util/log.hpp"

using namespace inspect;
using namespace inspect::server;
namespace asio = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using Json = nlohmann::json;

namespace {

/// Commands are not what is measured: the sink takes them and sends nothing.
struct NullSink : CommandSink {
  std::atomic<uint64_t> next{1};
  uint64_t setTeleop(const std::string&, double, double, double) override { return next++; }
  void clearTeleop(const std::string&) override {}
  uint64_t sendCommand(const std::string&, v1::Command) override { return next++; }
  void consoleAlive() override {}
};

/// A Beast client on its own thread: subscribes to every channel and, unless
/// it is the slow one, reads everything and times the telemetry.
class Client {
 public:
  Client(uint16_t port, bool reads) : reads_(reads) {
    ws_.next_layer().connect({asio::ip::make_address("127.0.0.1"), port});
    const timeval tv{2, 0};
    ::setsockopt(ws_.next_layer().native_handle(), SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    if (!reads_) {
      // The slow client's window stays small: its queue on the server fills at once.
      const int small = 16 * 1024;
      ::setsockopt(ws_.next_layer().native_handle(), SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
    }
    ws_.set_option(websocket::stream_base::decorator(
        [](websocket::request_type& r) { r.set(beast::http::field::sec_websocket_protocol, "foxglove.websocket.v1"); }));
    ws_.handshake("127.0.0.1", "/");
    thread_ = std::thread([this] { run(); });
  }
  ~Client() {
    stop_ = true;
    beast::error_code ec;
    ws_.next_layer().shutdown(tcp::socket::shutdown_both, ec);
    if (thread_.joinable()) thread_.join();
  }
  bool subscribed() const { return subscribed_.load(); }
  std::vector<double> latenciesMs() {
    std::lock_guard lk(mu_);
    return lat_ms_;
  }
  uint64_t telemetry() const { return telemetry_.load(); }
  void reset() {
    std::lock_guard lk(mu_);
    lat_ms_.clear();
    telemetry_ = 0;
  }

 private:
  void run() {
    beast::flat_buffer b;
    uint32_t next_sub = 1;
    while (!stop_) {
      beast::error_code ec;
      b.clear();
      if (!reads_ && subscribed_) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));  // never reads again
        continue;
      }
      ws_.read(b, ec);
      if (ec) {
        if (ec == beast::error::timeout || ec.value() == EAGAIN) continue;
        return;
      }
      const std::string msg = beast::buffers_to_string(b.data());
      if (ws_.got_text()) {
        const auto j = Json::parse(msg, nullptr, false);
        if (j.is_object() && j.value("op", "") == "advertise") {
          Json subs = Json::array();
          for (const auto& c : j["channels"]) {
            const uint32_t id = next_sub++;
            if (c["topic"].get<std::string>().ends_with("/telemetry") && telemetry_sub_ == 0) telemetry_sub_ = id;
            subs.push_back({{"id", id}, {"channelId", c["id"]}});
          }
          ws_.text(true);
          ws_.write(asio::buffer(Json{{"op", "subscribe"}, {"subscriptions", subs}}.dump()));
          if (telemetry_sub_) subscribed_ = true;
        }
        continue;
      }
      if (msg.size() < 13 || msg[0] != 1) continue;
      uint32_t sub = 0;
      for (int i = 0; i < 4; ++i) sub |= static_cast<uint32_t>(static_cast<unsigned char>(msg[1 + i])) << (8 * i);
      if (sub != telemetry_sub_) continue;
      v1::Telemetry t;
      if (!t.ParseFromArray(msg.data() + 13, static_cast<int>(msg.size() - 13))) continue;
      const double ms = static_cast<double>(monoNowUs() - t.robot_time_us()) / 1000.0;
      std::lock_guard lk(mu_);
      lat_ms_.push_back(ms);
      ++telemetry_;
    }
  }
  asio::io_context ioc_;
  websocket::stream<tcp::socket> ws_{ioc_};
  bool reads_;
  std::atomic<bool> stop_{false}, subscribed_{false};
  uint32_t telemetry_sub_ = 0;
  std::mutex mu_;
  std::vector<double> lat_ms_;
  std::atomic<uint64_t> telemetry_{0};
  std::thread thread_;
};

double pct(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(p / 100.0 * static_cast<double>(v.size())))];
}

struct Case {
  std::string name;
  int clients = 0;
  bool slow = false;
  double p50 = 0, p99 = 0, max = 0;
  double rate_hz = 0;  // telemetry per reading client per second (sent: 50)
  double call_p50_us = 0, call_p99_us = 0, call_max_us = 0;
  uint64_t slow_dropped = 0, slow_queued_kib = 0;
};

/// One case: its clients connected and subscribed, then `seconds` (20 s for
/// the client that never reads, to fill its queue) of telemetry and video;
/// the readers' latencies, the link's call times, the slow client's drops.
void measureCase(Case& c, uint16_t port, server::foxglove::FoxgloveBridge& bridge, double seconds, bool quick,
                 std::mutex& call_mu, std::vector<double>& call_us) {
  std::vector<std::unique_ptr<Client>> clients;
  for (int i = 0; i < c.clients; ++i) clients.push_back(std::make_unique<Client>(port, true));
  std::unique_ptr<Client> slow;
  if (c.slow) slow = std::make_unique<Client>(port, false);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (std::chrono::steady_clock::now() < deadline) {
    bool all = !slow || slow->subscribed();
    for (const auto& cl : clients) all = all && cl->subscribed();
    if (all) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // warm: connections settled
  for (const auto& cl : clients) cl->reset();
  {
    std::lock_guard lk(call_mu);
    call_us.clear();
  }
  // The client that never reads fills its queue (and the kernel's buffers, a few MB) in ~20 s.
  const double run_s = c.slow && !quick ? std::max(seconds, 20.0) : seconds;
  std::this_thread::sleep_for(std::chrono::duration<double>(run_s));
  std::vector<double> lat;
  uint64_t tel = 0;
  for (const auto& cl : clients) {
    const auto l = cl->latenciesMs();
    lat.insert(lat.end(), l.begin(), l.end());
    tel += cl->telemetry();
  }
  c.p50 = pct(lat, 50);
  c.p99 = pct(lat, 99);
  c.max = lat.empty() ? 0 : *std::max_element(lat.begin(), lat.end());
  c.rate_hz = static_cast<double>(tel) / c.clients / run_s;
  {
    std::lock_guard lk(call_mu);
    c.call_p50_us = pct(call_us, 50);
    c.call_p99_us = pct(call_us, 99);
    c.call_max_us = call_us.empty() ? 0 : *std::max_element(call_us.begin(), call_us.end());
  }
  if (c.slow)
    for (const auto& info : bridge.clients())
      if (info.counters.dropped_data + info.counters.dropped_video + info.counters.skipped_video > c.slow_dropped) {
        c.slow_dropped = info.counters.dropped_data + info.counters.dropped_video + info.counters.skipped_video;
        c.slow_queued_kib = info.queued_bytes / 1024;
      }
  clients.clear();
  slow.reset();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the server lets the connections go
}

/// The table, and the same figures as JSON (--json).
void report(const std::vector<Case>& cases, double seconds, const std::string& json_path) {
  const double ref = cases[0].p50 > 0 ? cases[0].p50 : 1;
  std::printf("bench_foxglove: telemetry 50 Hz + camera 30 fps (8 KB, 40 KB keyframes) through the bridge, %.1f s per case\n\n",
              seconds);
  std::printf("%-34s %9s %9s %9s %8s %10s %12s %12s %10s %10s\n", "case", "p50 ms", "p99 ms", "max ms", "vs 1", "tel Hz",
              "call p99 us", "call max us", "slow drops", "slow KiB");
  for (const auto& c : cases)
    std::printf("%-34s %9.3f %9.3f %9.3f %7.2fx %10.1f %12.1f %12.1f %10llu %10llu\n", c.name.c_str(), c.p50, c.p99,
                c.max, c.p50 / ref, c.rate_hz, c.call_p99_us, c.call_max_us,
                static_cast<unsigned long long>(c.slow_dropped), static_cast<unsigned long long>(c.slow_queued_kib));
  std::printf("\nlatency: the link's call into the bridge -> the client has read the message (all reading clients).\n"
              "vs 1 = p50 / the 1-client p50. tel Hz = telemetry per reading client per second (50 sent).\n"
              "call = how long the link's call into the bridge took (serialize + queue; never waits for a client).\n"
              "slow = the client that never reads: messages dropped for it, and its queue at the end (bounded:\n"
              "512 KiB data + 1 MiB video in this benchmark; the server's defaults are 2 + 4 MiB).\n");
  if (!json_path.empty()) {
    Json j{{"seconds", seconds}, {"cases", Json::array()}};
    for (const auto& c : cases)
      j["cases"].push_back({{"name", c.name}, {"clients", c.clients}, {"slow_client", c.slow}, {"p50_ms", c.p50},
                            {"p99_ms", c.p99}, {"max_ms", c.max}, {"p50_vs_1_client", c.p50 / ref},
                            {"telemetry_hz_per_client", c.rate_hz}, {"call_p50_us", c.call_p50_us},
                            {"call_p99_us", c.call_p99_us}, {"call_max_us", c.call_max_us},
                            {"slow_client_dropped", c.slow_dropped}, {"slow_client_queued_kib", c.slow_queued_kib}});
    std::ofstream(json_path) << j.dump(2) << "\n";
  }
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 5;
  bool quick = false;
  std::string json_path;
  cli::readOrExit("bench_foxglove", argc, argv, [&](cli::ArgReader& a) {
    if (a.isHelp()) {
      std::printf("usage: bench_foxglove [--seconds S] [--json FILE] [--quick]\n"
                  "Telemetry latency through the Foxglove bridge to 1 and 10 clients, and 10 with one that never\n"
                  "reads (that case runs 20 s: its queue fills); a table, --json writes the same figures. --quick: 1.5 s\n"
                  "per case.\n");
      std::exit(0);
    } else if (a.is("--seconds")) seconds = a.numberAbove(0.5);
    else if (a.is("--json")) json_path = a.path();
    else if (a.is("--quick")) {
      seconds = 1.5;
      quick = true;
    }
    else a.unknown();
  });
  log::setLevel(log::Level::kWarn);

  asio::io_context ioc;
  RobotRegistry registry;
  NullSink sink;
  ControlArbiter control;
  scene::SiteMaps maps;
  server::foxglove::FoxgloveBridge::Options o;
  o.server.bind = "127.0.0.1";
  o.server.port = 0;
  // Smaller send queues than the defaults (2 MiB data, 4 MiB video) so that the
  // client that never reads fills its queue within seconds, not a minute.
  o.server.limits.data_bytes = 512u << 10;
  o.server.limits.video_bytes = 1u << 20;
  server::foxglove::FoxgloveBridge bridge(ioc, o, registry, sink, control, maps, scene::Geometry{}, Console::Options{}, nullptr);
  const uint16_t port = bridge.start().port();
  auto guard = asio::make_work_guard(ioc);
  std::vector<std::thread> io;
  for (int i = 0; i < 2; ++i) io.emplace_back([&] { ioc.run(); });

  // The robot: connected, its channels advertised on its first envelope.
  v1::Hello hello;
  hello.set_robot_id("robot1");
  registry.onConnected("robot1", "127.0.0.1:1", 1, hello, monoNowNs());
  std::atomic<bool> feeding{true};
  std::mutex call_mu;
  std::vector<double> call_us;
  // The link: telemetry at 50 Hz, each stamped with its arrival time; the video receiver: 30 fps.
  std::thread link([&] {
    v1::Envelope env;
    auto* t = env.mutable_telemetry();
    for (int i = 0; i < 4; ++i) t->add_ultrasonic_m(1.0 + i);
    t->set_mode(v1::IDLE);
    auto next = std::chrono::steady_clock::now();
    while (feeding) {
      t->set_robot_time_us(monoNowUs());
      const int64_t a = monoNowNs();
      bridge.onEnvelope("robot1", env, true, monoNowUs());
      const double us = static_cast<double>(monoNowNs() - a) / 1000.0;
      {
        std::lock_guard lk(call_mu);
        call_us.push_back(us);
      }
      next += std::chrono::milliseconds(20);
      std::this_thread::sleep_until(next);
    }
  });
  std::thread camera([&] {
    video::Frame f;
    uint32_t n = 0;
    auto next = std::chrono::steady_clock::now();
    while (feeding) {
      f.keyframe = n % 30 == 0;
      f.annexb.assign(f.keyframe ? 40000 : 8000, 0x55);
      bridge.onAccessUnit("robot1", v1::PTZ_HEAD, f, monoNowUs());
      ++n;
      next += std::chrono::microseconds(33333);
      std::this_thread::sleep_until(next);
    }
  });

  std::vector<Case> cases{{"1 client", 1, false}, {"10 clients", 10, false}, {"10 clients + 1 that never reads", 10, true}};
  for (auto& c : cases) measureCase(c, port, bridge, seconds, quick, call_mu, call_us);
  feeding = false;
  link.join();
  camera.join();
  bridge.stop();
  guard.reset();
  ioc.stop();
  for (auto& t : io) t.join();

  report(cases, seconds, json_path);
  return 0;
}
