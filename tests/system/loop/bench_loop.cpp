// bench_loop: the robot's control loop with the camera on (docs/deploy.md
// "The loop's budget"). The real programs on loopback (mcu_sim on a pty,
// robot_client confined to one core with `taskset` and streaming 640x480 at
// 30 fps through libx264, pc_server receiving and decoding) while the robot
// drives a circle; then:
//   - sensor frame in -> wheel command out, as robot_client measures it from
//     the read of the frame's bytes to the command handed to the serial port
//     (util::LatencyHistogram; SIGUSR1 starts the window after a warm-up,
//     the figures are logged at its stop): p50, p99, max and the frames over
//     one 100 Hz period (a missed deadline);
//   - the CPU of each of robot_client's threads (/proc, utime + stime) and
//     the encoder's time per frame (the server's `video stats`);
//   - the budget on a Raspberry Pi: those per-core figures scaled by the
//     ratio of this machine's single-core `sysbench cpu` score to the Pi 4's
//     and Pi 5's published ones (docs/deploy.md cites them), against 60 % of
//     the Pi's four cores.
// The reference, measured in the same window on the same core: a thread at
// the loop's priority (SCHED_FIFO 10) that only wakes every 10 ms and records
// how late it woke, and the guest's steal time (/proc/stat): what the machine
// itself costs a loop that does nothing.
// A table for people; --json FILE writes the same figures.
#include <sched.h>
#include <pthread.h>
#include <signal.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <thread>

#include "shared/util/cli_args.hpp"
#include "shared/util/clock.hpp"
#include "shared/util/latency_histogram.hpp"
#include "shared/util/realtime.hpp"
#include "tests/support/process.hpp"
#include "tests/support/stack.hpp"

using namespace inspect::test;

namespace {

// sysbench 1.0.20 `sysbench cpu --threads=1 run` (primes up to 10000),
// events/s on one core, as published at
// https://leoncode.co.uk/articles/raspberry-pi-benchmarks (Raspberry Pi OS).
constexpr double kPi4SysbenchEps = 1477.83;
constexpr double kPi5SysbenchEps = 2737.49;
constexpr int kPiCores = 4;
constexpr double kPiBudgetShare = 0.60;  // of the Pi's cores

struct Options {
  double seconds = 600;
  int cpu = -1;  // -1: the last core
  bool smoke = false;
  bool people = false;  // the simulated camera with people in view: the people detector runs too
  bool wide_head = false;  // ...and the wide head's camera and detector (issue 61)
  std::string json;
};

struct ThreadCpu {
  std::string name;
  double percent = 0;  // of one core over the window
};

// The numbers on the line after `label` in `text`.
std::vector<double> numbersAfter(const std::string& text, const std::string& label) {
  std::vector<double> v;
  const auto p = text.rfind(label);
  if (p == std::string::npos) return v;
  const std::string line = text.substr(p + label.size(), text.find('\n', p) - p - label.size());
  static const std::regex kNum(R"([-+]?[0-9]+(\.[0-9]+)?)");
  for (std::sregex_iterator it(line.begin(), line.end(), kNum), end; it != end; ++it) v.push_back(std::stod(it->str()));
  return v;
}

// Steal time of the whole machine so far, s (/proc/stat "cpu" line, 8th value).
double stealS() {
  std::istringstream in(readFile("/proc/stat"));
  std::string cpu;
  double v[8] = {};
  in >> cpu;
  for (double& x : v) in >> x;
  return v[7] / static_cast<double>(::sysconf(_SC_CLK_TCK));
}

// The reference loop: on `cpu` at SCHED_FIFO `priority`, wakes every 10 ms
// (absolute deadlines) until `stop`, recording how late each wake-up was.
void referenceLoop(int cpu, int priority, const std::atomic<bool>& stop, inspect::util::LatencyHistogram& late,
                   std::string& why) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  ::pthread_setaffinity_np(::pthread_self(), sizeof set, &set);
  why = inspect::util::enterRealtime(priority);
  timespec next{};
  ::clock_gettime(CLOCK_MONOTONIC, &next);
  while (!stop.load()) {
    next.tv_nsec += 10'000'000;
    if (next.tv_nsec >= 1'000'000'000) next.tv_nsec -= 1'000'000'000, ++next.tv_sec;
    ::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
    timespec now{};
    ::clock_gettime(CLOCK_MONOTONIC, &now);
    late.record((now.tv_sec - next.tv_sec) * 1'000'000'000LL + (now.tv_nsec - next.tv_nsec));
  }
}

// This machine's single-core sysbench score (events/s), or NaN without sysbench.
double sysbenchEps(double seconds) {
  const std::string cmd = "sysbench cpu --threads=1 --time=" + std::to_string(static_cast<int>(seconds)) +
                          " run 2>/dev/null";
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return std::nan("");
  std::string out;
  char buf[512];
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  ::pclose(p);
  const auto v = numbersAfter(out, "events per second:");
  return v.empty() ? std::nan("") : v[0];
}

const char* kUsage = R"(usage: bench_loop [options]

The robot's control loop with the camera on: sensor frame in -> wheel command
out (p50/p99/max, frames over 10 ms), CPU per robot_client thread, the
encoder's time per frame, and the budget on a Raspberry Pi 4 and 5
(docs/deploy.md). robot_client and its encoder share one core (taskset).

  --seconds S   how long the robot drives (default 600)
  --quick       60 s
  --smoke       5 s, no sysbench (ctest's smoke run)
  --cpu N       the core for robot_client (default: the last one)
  --people      the camera is mcu_sim's (sim:) with two people walking round the
                robot's circle, so robot_client's people detector runs as well
  --wide-head   with --people: the wide head too (mcu_sim --wide-camera, robot_client
                --wide-video-source): both heads' detectors on the one core
  --json FILE   write the figures as JSON
  --help        this text
)";

}  // namespace

int main(int argc, char** argv) {
  Options o;
  inspect::cli::readOrExit("bench_loop", argc, argv, [&](inspect::cli::ArgReader& a) {
    if (a.isHelp()) {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else if (a.is("--seconds")) {
      o.seconds = a.number(2, 24 * 3600);
    } else if (a.is("--quick")) {
      o.seconds = 60;
    } else if (a.is("--smoke")) {
      o.seconds = 5;
      o.smoke = true;
    } else if (a.is("--cpu")) {
      o.cpu = static_cast<int>(a.integer(0, 4095));
    } else if (a.is("--people")) {
      o.people = true;
    } else if (a.is("--wide-head")) {
      o.wide_head = true;
    } else if (a.is("--json")) {
      o.json = a.path();
    } else {
      a.unknown();
    }
  });
  if (o.wide_head && !o.people) {
    std::fprintf(stderr, "bench_loop: --wide-head needs --people\n");
    return 2;
  }
  const int ncpu = static_cast<int>(::sysconf(_SC_NPROCESSORS_ONLN));
  if (o.cpu < 0) o.cpu = ncpu - 1;
  if (o.cpu >= ncpu) {
    std::fprintf(stderr, "bench_loop: --cpu %d: this machine has %d cores\n", o.cpu, ncpu);
    return 2;
  }

  Stack s("loop");
  s.enableVideo();
  s.setClientPrefix({"/usr/bin/taskset", "-c", std::to_string(o.cpu)});
  const double warmup_s = o.smoke ? 1.0 : 3.0;
  // A circle of radius 0.5 m in the empty world, re-sent by the console.
  const std::string script = "expect robots >= 1 within 20\nexpect sensor_hz > 50 within 5\ndrive 0.2 0.4\nwait " +
                             std::to_string(warmup_s + o.seconds + 1.0) + "\nvideo stats\nstop\nwait 0.5\n";
  if (!s.startServer(script)) {
    std::fprintf(stderr, "bench_loop: pc_server did not start\n%s", s.logs().c_str());
    return 1;
  }
  std::vector<std::string> sim_args, client_args;
  std::string world = "empty.yaml";
  if (o.people) {
    // Two people walking round a 3 m square about the robot's 0.5 m circle: in view part of each turn.
    world = s.dir() / "people.yaml";
    writeFile(world, "name: loop_people\nstart: {x_m: 0, y_m: 0, theta_rad: 0}\npedestrians:\n"
                     "  - {id: a, speed_m_s: 0.8, loop: true, route_m: [3, -2.5, 3, 3.5, -3, 3.5, -3, -2.5]}\n"
                     "  - {id: b, speed_m_s: 1.1, loop: true, route_m: [-3, 3.5, -3, -2.5, 3, -2.5, 3, 3.5]}\n");
    const std::string slot = "/dev/shm/inspect-bench-loop-" + std::to_string(::getpid());
    sim_args = {"--camera", slot};
    client_args = {"--video-source", "sim:" + slot};
    if (o.wide_head) {
      sim_args.insert(sim_args.end(), {"--wide-camera", slot + "-wide"});
      client_args.insert(client_args.end(), {"--wide-video-source", "sim:" + slot + "-wide"});
    }
  }
  auto& robot = s.startRobot("robot1", world, {}, sim_args, client_args);
  // Measure once the robot drives and the stream runs.
  if (!waitUntil([&] { return s.serverOutput().find("drive +0.20") != std::string::npos; }, 30.0)) {
    std::fprintf(stderr, "bench_loop: the robot never drove\n%s", s.logs().c_str());
    return 1;
  }
  sleepS(warmup_s);
  // The window starts here: robot_client logs its figures so far and counts anew.
  ::kill(robot.client.pid(), SIGUSR1);
  const long hz = ::sysconf(_SC_CLK_TCK);
  const auto cpu0 = threadCpuTicks(robot.client.pid());
  const double steal0 = stealS();
  const int64_t t0 = inspect::monoNowNs();
  std::atomic<bool> stop_ref{false};
  inspect::util::LatencyHistogram ref;
  std::string ref_why;
  std::thread ref_thread(referenceLoop, o.cpu, 10, std::cref(stop_ref), std::ref(ref), std::ref(ref_why));
  sleepS(o.seconds);
  stop_ref = true;
  ref_thread.join();
  const auto cpu1 = threadCpuTicks(robot.client.pid());
  const double wall_s = static_cast<double>(inspect::monoNowNs() - t0) * 1e-9;
  const double steal_pct = 100.0 * (stealS() - steal0) / wall_s / ncpu;
  const auto rc = s.server().wait(30.0);
  robot.client.terminate();
  const std::string client_err = readFile(s.dir() / "robot1-client.err");
  const std::string server_out = s.serverOutput();

  // robot_client's own figures: "N frames; p50 X ms, p99 Y ms, max Z ms; over 10 ms: K".
  const auto loop = numbersAfter(client_err, "sensor frame in -> wheel command out: ");
  const auto frames = numbersAfter(server_out, "  robot frames: ");  // captured, encoded, dropped, keyframes, requested, ms
  if (loop.size() < 6 || frames.size() < 6 || !rc) {
    std::fprintf(stderr, "bench_loop: missing figures (loop %zu, video %zu)\n%s", loop.size(), frames.size(),
                 s.logs().c_str());
    return 1;
  }
  const double n = loop[0], p50 = loop[2], p99 = loop[4], mx = loop[5];
  const double missed = loop.size() > 7 ? loop[7] : loop.back();
  const double encode_ms = frames[5];

  std::vector<ThreadCpu> threads;
  double total_pct = 0;
  for (const auto& [name, t] : cpu1) {
    const double d = t - (cpu0.count(name) ? cpu0.at(name) : 0.0);
    const double pct = 100.0 * d / static_cast<double>(hz) / wall_s;
    threads.push_back({name, pct});
    total_pct += pct;
  }
  std::sort(threads.begin(), threads.end(), [](const ThreadCpu& a, const ThreadCpu& b) { return a.percent > b.percent; });

  std::printf("\nbench_loop: %.0f s, robot_client on core %d of %d with libx264 640x480 at 30 fps%s\n\n", wall_s, o.cpu,
              ncpu, o.wide_head ? ", both heads' people detectors" : o.people ? ", the PTZ head's people detector" : "");
  const double ref_p50 = static_cast<double>(ref.quantileNs(0.5)) * 1e-6,
               ref_p99 = static_cast<double>(ref.quantileNs(0.99)) * 1e-6, ref_max = static_cast<double>(ref.maxNs()) * 1e-6;
  std::printf("| | robot_client: sensor frame in -> wheel command out | reference: 10 ms wake-up, how late |\n|---|---|---|\n");
  std::printf("| samples | %.0f | %llu |\n| p50 | %.3f ms | %.3f ms |\n| p99 | %.3f ms | %.3f ms |\n"
              "| max | %.3f ms | %.3f ms |\n| over 10 ms (missed) | %.0f | %llu |\n\n",
              n, static_cast<unsigned long long>(ref.count()), p50, ref_p50, p99, ref_p99, mx, ref_max, missed,
              static_cast<unsigned long long>(ref.overDeadline()));
  std::printf("reference: a thread on core %d at SCHED_FIFO 10 that does nothing but wake%s; steal time "
              "(the hypervisor ran something else) %.1f %% of the machine in the window\n\n",
              o.cpu, ref_why.empty() ? "" : (" (" + ref_why + ")").c_str(), steal_pct);
  std::printf("| robot_client thread | CPU %% of one core |\n|---|---|\n");
  for (const auto& t : threads) std::printf("| %s | %.1f |\n", t.name.c_str(), t.percent);
  std::printf("| all | %.1f |\n\nencoder: %.2f ms per frame (libx264, the server's video stats)\n", total_pct, encode_ms);
  // Each head's detection pace, from the server's `video stats` (the robot's telemetry).
  std::string heads_json;
  for (const auto& [label, key] : {std::pair{"robot people: ", "ptz"}, std::pair{"robot wide head: ", "wide"}}) {
    const auto at = server_out.rfind(label);
    if (at == std::string::npos) continue;
    const std::string line = server_out.substr(at, server_out.find('\n', at) - at);
    std::smatch m;
    if (!std::regex_search(line, m, std::regex(R"(on ([0-9]+x[0-9]+), ([0-9.]+) Hz, ([0-9.]+) ms, ([0-9]+) pictures)")))
      continue;
    std::printf("%s head: %s at %s Hz, %s ms a picture, %s pictures\n", key, m[1].str().c_str(), m[2].str().c_str(),
                m[3].str().c_str(), m[4].str().c_str());
    heads_json += std::string(heads_json.empty() ? "" : ", ") + "\"" + key + "\": {\"size\": \"" + m[1].str() +
                  "\", \"hz\": " + m[2].str() + ", \"ms\": " + m[3].str() + ", \"pictures\": " + m[4].str() + "}";
  }

  std::string json = "{\n  \"seconds\": " + std::to_string(wall_s) + ",\n  \"cpu\": " + std::to_string(o.cpu) +
                     ",\n  \"frames\": " + std::to_string(static_cast<long long>(n)) +
                     ",\n  \"frame_to_command_ms\": {\"p50\": " + std::to_string(p50) + ", \"p99\": " +
                     std::to_string(p99) + ", \"max\": " + std::to_string(mx) + "},\n  \"missed_deadlines\": " +
                     std::to_string(static_cast<long long>(missed)) + ",\n  \"reference_late_ms\": {\"p50\": " +
                     std::to_string(ref_p50) + ", \"p99\": " + std::to_string(ref_p99) + ", \"max\": " +
                     std::to_string(ref_max) + ", \"over_10ms\": " + std::to_string(ref.overDeadline()) +
                     "},\n  \"steal_percent\": " + std::to_string(steal_pct) + ",\n  \"encode_ms_per_frame\": " +
                     std::to_string(encode_ms) + ",\n  \"thread_cpu_percent\": {";
  for (std::size_t i = 0; i < threads.size(); ++i)
    json += (i ? ", \"" : "\"") + threads[i].name + "\": " + std::to_string(threads[i].percent);
  json += "},\n  \"total_cpu_percent\": " + std::to_string(total_pct);
  json += ",\n  \"people\": " + std::string(o.people ? "true" : "false") + ",\n  \"wide_head\": " +
          (o.wide_head ? "true" : "false") + ",\n  \"detection\": {" + heads_json + "}";

  if (!o.smoke) {
    const double eps = sysbenchEps(10);
    if (std::isnan(eps)) {
      std::printf("\nno sysbench here (apt install sysbench): no Pi budget\n");
    } else {
      std::printf("\nPi budget (this core: sysbench cpu %.0f events/s, one thread)\n\n", eps);
      std::printf("| Pi | slower by | loop p99 | robot_client CPU | of the Pi's 4 cores | within 60 %% |\n|---|---|---|---|---|---|\n");
      json += ",\n  \"sysbench_events_per_s\": " + std::to_string(eps) + ",\n  \"pi\": [";
      const std::pair<const char*, double> pis[] = {{"Pi 4", kPi4SysbenchEps}, {"Pi 5", kPi5SysbenchEps}};
      for (std::size_t i = 0; i < 2; ++i) {
        const double f = eps / pis[i].second;
        const double cpu = total_pct * f;  // % of one Pi core
        const double share = cpu / (100.0 * kPiCores);
        std::printf("| %s | %.2f | %.3f ms | %.0f %% of a core | %.0f %% | %s |\n", pis[i].first, f, p99 * f, cpu,
                    100 * share, share <= kPiBudgetShare ? "yes" : "NO");
        json += std::string(i ? ", " : "") + "{\"name\": \"" + pis[i].first + "\", \"factor\": " + std::to_string(f) +
                ", \"loop_p99_ms\": " + std::to_string(p99 * f) + ", \"cpu_percent_of_core\": " +
                std::to_string(cpu) + ", \"share_of_cores\": " + std::to_string(share) + "}";
      }
      json += "]";
    }
  }
  json += "\n}\n";
  if (!o.json.empty()) writeFile(o.json, json);
  // The smoke run checks that every figure came out; the targets (p99 < 2 ms,
  // 0 missed) are judged from the long run's table, not here.
  return n > 0 ? 0 : 1;
}
