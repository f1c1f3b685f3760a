// soak: the whole system for hours (issue 38, docs/load.md): does anything
// grow, leak or get lost when nothing is restarted by hand?
//
// One real pc_server (mutual TLS, video on, every robot recorded) carries
//   - one full stack: mcu_sim + robot_client with its event journal, video
//     on, in outage_check's world (gas alarms raised and cleared all along),
//     reaching the server through tcp_fault_relay, whose link is cut for
//     0.5-5 s every --cut-every-s seconds;
//   - --robots simulated robots over TLS (tests/support/fake_robot), telemetry
//     at --hz, each sending an INFO event every 5 s while its run records.
// Every --restart-min minutes pc_server ends its script (record stop, exit)
// and is started again on the same ports and runs directory: the robots come
// back, robot1 replays what it stored meanwhile.
//
// Every --sample-s seconds it prints a row: RSS, file descriptors, threads and
// CPU of pc_server, robot_client and mcu_sim, the catalog's, the MCAPs' and
// the video's bytes on disk, alarm transitions logged vs in the catalog. At the
// end, the verdict:
//   - no growth: in each process's life (pc_server: each incarnation), RSS
//     after its first --ref-min minutes stays within +5 % of the level it had
//     then, and file descriptors and threads do not rise above it;
//   - nothing lost: every alarm transition robot_client logged is in the
//     catalog exactly once, in order, at the robot's time (within 100 ms);
//     every event a simulated robot sent during its run is in the catalog
//     once; no telemetry missing or doubled inside a recorded run.
// A table for people and, with --json FILE, every sample and figure.
//
//   soak [--hours H] [--robots N] [--hz HZ] [--restart-min M] [--cut-every-s S]
//        [--sample-s S] [--ref-min M] [--seed N] [--json FILE]
#include <sqlite3.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>

#include "shared/util/cli_args.hpp"
#include "tests/support/fake_robot/fleet_robot.hpp"
#include "tests/support/stack.hpp"
#include "tests/support/test_certs.hpp"
#include "tests/system/faults/gas_outage_world.hpp"
#include "tests/system/link/server_harness.hpp"

using namespace inspect;
using namespace inspect::test;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

struct Options {
  double hours = 0.5;
  int robots = 10;
  double hz = 100.0;
  double restart_min = 10.0;
  double cut_every_s = 60.0;
  double min_cut_s = 0.5, max_cut_s = 5.0;
  double sample_s = 30.0;
  double ref_min = 5.0;
  unsigned seed = 1;
  std::string json;
};

constexpr double kEventPeriodS = 5.0;
// No cut and no fleet event this close to an incarnation's end: its script
// stops the runs then, and what a robot sends must land in a run.
constexpr double kQuietEndS = 30.0;

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
Clock::time_point inS(double s) {
  return Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

// One process's figures at one instant.
struct ProcFigures {
  bool ok = false;
  double rss_mb = 0, cpu_pct = 0;
  int fds = 0, threads = 0;
};

int countFds(pid_t pid) {
  std::error_code ec;
  int n = 0;
  for (fs::directory_iterator it("/proc/" + std::to_string(pid) + "/fd", ec), end; !ec && it != end; it.increment(ec))
    ++n;
  return n;
}

// CPU between two samples of the same process (pid); the first sample of a pid reports 0.
class ProcWatch {
 public:
  ProcFigures sample(pid_t pid) {
    ProcFigures f;
    const auto s = linktest::sampleProc(pid);
    if (!s.ok) return f;
    f.ok = true;
    f.rss_mb = static_cast<double>(s.rss_kb) / 1024.0;
    f.threads = static_cast<int>(s.threads);
    f.fds = countFds(pid);
    const auto now = Clock::now();
    if (pid == pid_) {
      const double wall = std::chrono::duration<double>(now - t_).count();
      if (wall > 0)
        f.cpu_pct = 100.0 * static_cast<double>(s.cpu_ticks - ticks_) / linktest::clockTicksPerSecond() / wall;
    }
    pid_ = pid;
    ticks_ = s.cpu_ticks;
    t_ = now;
    return f;
  }

 private:
  pid_t pid_ = -1;
  uint64_t ticks_ = 0;
  Clock::time_point t_{};
};

uint64_t bytesUnder(const std::string& dir, const std::string& ext) {
  uint64_t n = 0;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file(ec) && (ext.empty() || it->path().extension() == ext)) n += it->file_size(ec);
  return n;
}

uint64_t fileBytes(const std::string& path) {
  std::error_code ec;
  const auto n = fs::file_size(path, ec);
  return ec ? 0 : n;
}

std::size_t countOf(const std::string& text, const std::string& needle) {
  std::size_t n = 0;
  for (auto at = text.find(needle); at != std::string::npos; at = text.find(needle, at + needle.size())) ++n;
  return n;
}

// One row of the time series.
struct Sample {
  double t_min = 0;
  int incarnation = 0;
  double server_age_min = 0;
  ProcFigures server, client, sim, self;
  double catalog_mb = 0, mcap_mb = 0, video_mb = 0;
  std::size_t alarms_logged = 0, alarms_cataloged = 0;
};

nlohmann::json toJson(const ProcFigures& p) {
  return {{"rss_mb", p.rss_mb}, {"fds", p.fds}, {"threads", p.threads}, {"cpu_pct", p.cpu_pct}};
}

// A process's life judged: the level in its first ref_min minutes against what came after.
struct Growth {
  std::string what;
  int samples_ref = 0, samples_after = 0;
  double rss_ref = 0, rss_after = 0;
  int fds_ref = 0, fds_after = 0, threads_ref = 0, threads_after = 0;
  bool judged() const { return samples_ref > 0 && samples_after >= 2; }
  // RSS within 5 % of the reference's peak; descriptors within kFdSlack of it (a connection in
  // its handshake or a file being rotated at the moment of a sample: a leak of one per cut or
  // reconnect grows past it within a process's life); no new threads.
  static constexpr int kFdSlack = 2;
  bool ok() const {
    return !judged() ||
           (rss_after <= rss_ref * 1.05 && fds_after <= fds_ref + kFdSlack && threads_after <= threads_ref);
  }
};

Growth judge(const std::string& what, const std::vector<std::pair<double, ProcFigures>>& life, double ref_min) {
  Growth g;
  g.what = what;
  for (const auto& [age_min, p] : life) {
    if (!p.ok) continue;
    if (age_min <= ref_min) {
      ++g.samples_ref;
      g.rss_ref = std::max(g.rss_ref, p.rss_mb);
      g.fds_ref = std::max(g.fds_ref, p.fds);
      g.threads_ref = std::max(g.threads_ref, p.threads);
    } else {
      ++g.samples_after;
      g.rss_after = std::max(g.rss_after, p.rss_mb);
      g.fds_after = std::max(g.fds_after, p.fds);
      g.threads_after = std::max(g.threads_after, p.threads);
    }
  }
  return g;
}

// Catalog counts of the fleet's soak events: total and distinct texts.
std::pair<int64_t, int64_t> catalogSoakEvents(const std::string& db) {
  std::pair<int64_t, int64_t> out{-1, -1};
  sqlite3* h = nullptr;
  if (sqlite3_open_v2(db.c_str(), &h, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_stmt* st = nullptr;
    if (sqlite3_prepare_v2(h, "SELECT COUNT(*), COUNT(DISTINCT text) FROM events WHERE text LIKE 'soak event %'", -1,
                           &st, nullptr) == SQLITE_OK &&
        sqlite3_step(st) == SQLITE_ROW)
      out = {sqlite3_column_int64(st, 0), sqlite3_column_int64(st, 1)};
    sqlite3_finalize(st);
  }
  sqlite3_close(h);
  return out;
}

// Telemetry of the simulated robots' runs: sequence numbers missing or doubled
// between the first and the last one each run recorded.
struct TelemetryCheck {
  int runs = 0;
  uint64_t recorded = 0, missing = 0, duplicates = 0;
  std::string error;
};

TelemetryCheck checkFleetRuns(const std::string& runs_dir, const std::string& prefix) {
  TelemetryCheck c;
  std::error_code ec;
  for (fs::directory_iterator it(runs_dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.find("-" + prefix) == std::string::npos || !fs::exists(it->path() / "run.mcap")) continue;
    try {
      const auto rec = linktest::readTelemetry((it->path() / "run.mcap").string());
      std::vector<uint64_t> seq;
      for (const auto& r : rec) seq.push_back(r.seq);
      std::sort(seq.begin(), seq.end());
      ++c.runs;
      c.recorded += seq.size();
      for (std::size_t i = 1; i < seq.size(); ++i) {
        if (seq[i] == seq[i - 1]) ++c.duplicates;
        else c.missing += seq[i] - seq[i - 1] - 1;
      }
    } catch (const std::exception& e) {
      c.error += name + ": " + e.what() + "; ";
    }
  }
  return c;
}

void control(const std::string& fifo, const std::string& cmd) { std::ofstream(fifo) << cmd << "\n"; }

// The simulated robots of one server incarnation, on an io_context of their own.
class Fleet {
 public:
  Fleet(const std::vector<std::string>& ids, const std::string& certs, uint16_t port, double hz, uint32_t seed)
      : guard_(boost::asio::make_work_guard(ioc_)) {
    for (std::size_t i = 0; i < ids.size(); ++i) {
      FleetRobotOptions o;
      o.id = ids[i];
      o.certs_dir = certs;
      o.port = port;
      o.telemetry_hz = hz;
      o.seed = seed + static_cast<uint32_t>(i);
      robots_.push_back(std::make_shared<FleetRobot>(ioc_, o));
    }
    thread_ = std::thread([this] { ioc_.run(); });
    for (auto& r : robots_) {
      r->start();
      r->startTelemetry();
    }
  }
  ~Fleet() {
    for (auto& r : robots_) r->close();
    sleepS(0.2);
    guard_.reset();
    ioc_.stop();
    if (thread_.joinable()) thread_.join();
  }
  std::vector<std::shared_ptr<FleetRobot>>& robots() { return robots_; }
  std::size_t accepted() const {
    return static_cast<std::size_t>(std::count_if(robots_.begin(), robots_.end(), [](const auto& r) {
      return r->stats().accepted && !r->stats().closed;
    }));
  }

 private:
  boost::asio::io_context ioc_{1};
  boost::asio::executor_work_guard<boost::asio::io_context::executor_type> guard_;
  std::vector<std::shared_ptr<FleetRobot>> robots_;
  std::thread thread_;
};

}  // namespace

int main(int argc, char** argv) {
  Options o;
  cli::readOrExit("soak", argc, argv, [&](cli::ArgReader& a) {
    if (a.isHelp()) {
      std::puts(
          "usage: soak [--hours H] [--robots N] [--hz HZ] [--restart-min M] [--cut-every-s S] [--sample-s S]\n"
          "            [--ref-min M] [--seed N] [--json FILE]\n"
          "  The whole system for --hours (0.5): one pc_server, one full stack (mcu_sim + robot_client with\n"
          "  video, link cut every --cut-every-s (60) s for 0.5-5 s), --robots (10) simulated robots at --hz\n"
          "  (100); pc_server restarted every --restart-min (10) minutes (0: never). A row every --sample-s\n"
          "  (30) s; growth judged against each process's first --ref-min (5) minutes. docs/load.md.\n"
          "  Exit status: 0 = no growth and nothing lost; 1 = not; 2 = bad arguments.");
      std::exit(0);
    } else if (a.is("--hours")) o.hours = a.number(0.01, 1000);
    else if (a.is("--robots")) o.robots = static_cast<int>(a.integer(0, 200));
    else if (a.is("--hz")) o.hz = a.number(1, 1000);
    else if (a.is("--restart-min")) o.restart_min = a.number(0, 10000);
    else if (a.is("--cut-every-s")) o.cut_every_s = a.number(5, 100000);
    else if (a.is("--sample-s")) o.sample_s = a.number(1, 3600);
    else if (a.is("--ref-min")) o.ref_min = a.number(0.1, 10000);
    else if (a.is("--seed")) o.seed = static_cast<unsigned>(a.integer(0, 1 << 30));
    else if (a.is("--json")) o.json = a.path();
    else a.unknown();
  });
  const double total_s = o.hours * 3600.0;
  const double inc_s = o.restart_min > 0 ? std::min(o.restart_min * 60.0, total_s) : total_s;

  std::vector<std::string> ids;
  for (int i = 1; i <= o.robots; ++i) ids.push_back(robotId("soak", i));
  std::vector<std::string> all_ids = ids;
  all_ids.insert(all_ids.begin(), "robot1");
  const std::string certs = testCertsDir(all_ids);

  Stack s("soak");
  s.enableVideo();
  writeFile(s.dir() / "gas_outages.yaml", gasOutageWorldYaml(total_s + 600));
  const std::string runs_dir = s.dir() / "runs";
  const std::string catalog = runs_dir + "/catalog.sqlite";

  // One incarnation's script: every robot recorded for `len_s`, then stopped; the script's end ends pc_server.
  const auto script = [&](int inc, double len_s) {
    std::string sc = "expect robots >= " + std::to_string(all_ids.size()) + " within 60\n";
    for (const auto& id : all_ids) sc += "select " + id + "\nrecord start soak" + std::to_string(inc) + "\n";
    sc += "wait " + std::to_string(static_cast<int>(std::lround(len_s))) + "\n";
    for (const auto& id : all_ids) sc += "select " + id + "\nrecord stop\n";
    return sc;
  };

  const auto t0 = Clock::now();
  int inc = 0;
  double len0 = inc_s;
  if (!s.startServer(script(inc, len0))) {
    std::fprintf(stderr, "soak: pc_server did not start\n%s", s.logs().c_str());
    return 1;
  }
  const int port = s.port(), video_port = s.videoPort();
  const std::string fifo = s.dir() / "relay.ctl";
  Process relay = Process::spawn({binPath("tcp_fault_relay"), "--target", "127.0.0.1:" + std::to_string(port),
                                  "--control", fifo, "--port-file", s.dir() / "relay.port"},
                                 s.dir() / "relay.out", s.dir() / "relay.err");
  if (!waitUntil([&] { return exists(s.dir() / "relay.port"); }, 10)) {
    std::fprintf(stderr, "soak: tcp_fault_relay did not start\n");
    return 1;
  }
  const int relay_port = std::atoi(readFile(s.dir() / "relay.port").c_str());
  auto& robot = s.startRobot("robot1", s.dir() / "gas_outages.yaml", {}, {},
                             {"--server", "127.0.0.1:" + std::to_string(relay_port), "--journal",
                              s.dir() / "robot1-events.journal"});

  std::printf("soak: %.2f h, pc_server restarted every %.0f min, robot1 (full stack, video, link cut every %.0f s "
              "for %.1f-%.1f s) + %d simulated robots at %.0f Hz; a row every %.0f s\n\n",
              o.hours, inc_s / 60.0, o.cut_every_s, o.min_cut_s, o.max_cut_s, o.robots, o.hz, o.sample_s);
  std::printf("| t min | inc | server RSS MB / fds / thr / CPU %% | client RSS MB / fds / thr / CPU %% | "
              "mcu_sim RSS MB / fds / thr / CPU %% | soak RSS MB / CPU %% | catalog MB | MCAP MB | video MB | "
              "alarms logged / cataloged |\n|---|---|---|---|---|---|---|---|---|---|\n");
  std::fflush(stdout);

  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> cut_len(o.min_cut_s, o.max_cut_s);
  ProcWatch w_server, w_client, w_sim, w_self;
  std::vector<Sample> samples;
  std::vector<std::vector<std::pair<double, ProcFigures>>> server_lives(1);
  std::vector<std::pair<double, ProcFigures>> client_life, sim_life;
  int cuts = 0, restarts = 0;
  uint64_t fleet_events_sent = 0;
  std::vector<std::string> problems;
  uint64_t end_unix_ns = 0;  // when the last pc_server had ended: later alarms cannot be in the catalog

  for (;; ++inc) {
    const auto inc_t0 = Clock::now();
    const double len_s = inc == 0 ? len0 : std::min(inc_s, std::max(60.0, total_s - since(t0)));
    const bool last = since(t0) + len_s >= total_s - 1.0;
    auto fleet = std::make_unique<Fleet>(ids, certs, static_cast<uint16_t>(port), o.hz, o.seed * 1000 + inc * 100);
    // The runs have started once the console confirmed one per robot.
    const std::size_t recording_before = countOf(s.serverOutput(), ": recording run ");
    std::optional<Clock::time_point> recording_since;
    auto next_cut = inS(o.cut_every_s / 2);
    bool cutting = false;  // a plain flag and time: GCC 12 warns falsely on an optional time_point here
    Clock::time_point cut_until{};
    auto next_event = Clock::now();
    auto next_sample = inc == 0 ? Clock::now() : inS(o.sample_s / 2);
    uint64_t event_k = 0;
    for (;;) {
      if (!s.server().running()) break;
      const auto now = Clock::now();
      if (!recording_since && countOf(s.serverOutput(), ": recording run ") >= recording_before + all_ids.size())
        recording_since = now;
      const bool quiet_end =
          recording_since && std::chrono::duration<double>(now - *recording_since).count() > len_s - kQuietEndS;
      // A cut: the link down for 0.5-5 s, then up until the next one (a cut ends before the quiet end).
      if (cutting && now >= cut_until) {
        control(fifo, "flow");
        cutting = false;
        next_cut = inS(o.cut_every_s);
      }
      if (recording_since && !quiet_end && !cutting && now >= next_cut) {
        control(fifo, "cut");
        ++cuts;
        cutting = true;
        cut_until = inS(cut_len(rng));
      }
      if (recording_since && !quiet_end && Clock::now() >= next_event &&
          Clock::now() > *recording_since + std::chrono::seconds(2)) {
        for (auto& r : fleet->robots())
          if (r->stats().accepted && !r->stats().closed) {
            r->sendEvent("soak event " + r->id() + " " + std::to_string(inc) + "." + std::to_string(event_k));
            ++fleet_events_sent;
          }
        ++event_k;
        next_event = inS(kEventPeriodS);
      }
      if (Clock::now() >= next_sample) {
        Sample sm;
        sm.t_min = since(t0) / 60.0;
        sm.incarnation = inc;
        sm.server_age_min = since(inc_t0) / 60.0;
        sm.server = w_server.sample(s.server().pid());
        sm.client = w_client.sample(robot.client.pid());
        sm.sim = w_sim.sample(robot.sim.pid());
        sm.self = w_self.sample(::getpid());
        sm.catalog_mb = static_cast<double>(fileBytes(catalog) + fileBytes(catalog + "-wal")) / 1e6;
        sm.mcap_mb = static_cast<double>(bytesUnder(runs_dir, ".mcap")) / 1e6;
        sm.video_mb = static_cast<double>(bytesUnder(s.videoDir(), "")) / 1e6;
        sm.alarms_logged = robotLoggedAlarms(s.dir() / "robot1-client.err").size();
        sm.alarms_cataloged = catalogAlarms(catalog, "robot_id", "robot1").size();
        samples.push_back(sm);
        server_lives.back().push_back({sm.server_age_min, sm.server});
        if (sm.client.ok) client_life.push_back({sm.t_min, sm.client});
        sim_life.push_back({sm.t_min, sm.sim});
        const auto pf = [](const ProcFigures& p) {
          char b[96];
          if (!p.ok) return std::string("-");
          std::snprintf(b, sizeof b, "%.1f / %d / %d / %.1f", p.rss_mb, p.fds, p.threads, p.cpu_pct);
          return std::string(b);
        };
        std::printf("| %.1f | %d | %s | %s | %s | %.1f / %.1f | %.2f | %.1f | %.1f | %zu / %zu |\n", sm.t_min, inc,
                    pf(sm.server).c_str(), pf(sm.client).c_str(), pf(sm.sim).c_str(), sm.self.rss_mb,
                    sm.self.cpu_pct, sm.catalog_mb, sm.mcap_mb, sm.video_mb, sm.alarms_logged, sm.alarms_cataloged);
        std::fflush(stdout);
        next_sample = inS(o.sample_s);
      }
      if (since(inc_t0) > len_s + 180) {
        problems.push_back("incarnation " + std::to_string(inc) + ": pc_server still running 180 s after its script's end");
        s.server().terminate();
        break;
      }
      sleepS(0.2);
    }
    if (cutting) control(fifo, "flow");
    const auto rc = s.server().wait(30);
    end_unix_ns = static_cast<uint64_t>(
        std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count());
    if (!recording_since) problems.push_back("incarnation " + std::to_string(inc) + ": the runs did not all start");
    if (!rc || *rc != 0)
      problems.push_back("incarnation " + std::to_string(inc) + ": pc_server's script " +
                         (rc ? "failed (exit " + std::to_string(*rc) + ")" : "did not end"));
    fleet.reset();
    if (last || since(t0) >= total_s - 60) break;
    // The restart: same ports, same runs directory.
    std::error_code ec;
    fs::remove(s.dir() / "port", ec);
    fs::remove(s.dir() / "video_port", ec);
    bool up = false;
    for (int attempt = 0; attempt < 10 && !up; ++attempt) {
      up = s.startServer(script(inc + 1, std::min(inc_s, std::max(60.0, total_s - since(t0)))),
                         {"--port", std::to_string(port), "--video-port", std::to_string(video_port)});
      if (!up) sleepS(1.0);
    }
    if (!up) {
      problems.push_back("pc_server did not start again on port " + std::to_string(port));
      break;
    }
    ++restarts;
    server_lives.emplace_back();
  }
  relay.terminate();
  robot.client.terminate();
  robot.sim.terminate();

  // Nothing lost: robot1's alarm transitions against the catalog, up to 1 s
  // before the last pc_server ended (what came later had no server to reach).
  const int64_t cutoff_ms = msOfDayLocal(end_unix_ns - 1'000'000'000ULL);
  auto logged = robotLoggedAlarms(s.dir() / "robot1-client.err");
  std::erase_if(logged, [&](const LoggedAlarm& a) { return dayDiffMs(a.ms_of_day, cutoff_ms) > 0; });
  auto cataloged = catalogAlarms(catalog, "robot_id", "robot1");
  std::erase_if(cataloged, [&](const CatalogAlarm& a) {
    return dayDiffMs(msOfDayLocal(static_cast<uint64_t>(a.time_unix * 1e9)), cutoff_ms) > 0;
  });
  std::size_t in_order = 0, time_ok = 0;
  int64_t worst_ms = 0;
  for (std::size_t i = 0; i < std::min(logged.size(), cataloged.size()); ++i) {
    const bool raised = logged[i].kind == "ALARM_RAISED";
    if (raised != (cataloged[i].state == "raised")) break;
    ++in_order;
    const int64_t d = std::abs(
        dayDiffMs(msOfDayLocal(static_cast<uint64_t>(cataloged[i].time_unix * 1e9)), logged[i].ms_of_day));
    worst_ms = std::max(worst_ms, d);
    time_ok += d <= 100;
  }
  const bool alarms_ok = !logged.empty() && cataloged.size() == logged.size() && in_order == logged.size() &&
                         time_ok == logged.size();
  const auto [ev_total, ev_distinct] = catalogSoakEvents(catalog);
  const bool events_ok = ev_total == static_cast<int64_t>(fleet_events_sent) && ev_distinct == ev_total;
  const auto tlm = checkFleetRuns(runs_dir, "soak");
  const bool tlm_ok = tlm.error.empty() && tlm.missing == 0 && tlm.duplicates == 0 && (o.robots == 0 || tlm.runs > 0);

  std::vector<Growth> growth;
  for (std::size_t i = 0; i < server_lives.size(); ++i)
    growth.push_back(judge("pc_server (incarnation " + std::to_string(i) + ")", server_lives[i], o.ref_min));
  growth.push_back(judge("robot_client", client_life, o.ref_min));
  growth.push_back(judge("mcu_sim", sim_life, o.ref_min));
  const bool growth_ok = std::all_of(growth.begin(), growth.end(), [](const Growth& g) { return g.ok(); });
  const bool pass = problems.empty() && alarms_ok && events_ok && tlm_ok && growth_ok;

  std::printf("\n| process | RSS MB first %.1f min -> after (max) | fds | threads | verdict |\n|---|---|---|---|---|\n",
              o.ref_min);
  for (const auto& g : growth) {
    if (!g.judged()) {
      std::printf("| %s | (%d + %d samples: too short to judge) | | | - |\n", g.what.c_str(), g.samples_ref,
                  g.samples_after);
      continue;
    }
    std::printf("| %s | %.1f -> %.1f (%+.1f %%) | %d -> %d | %d -> %d | %s |\n", g.what.c_str(), g.rss_ref,
                g.rss_after, 100.0 * (g.rss_after / g.rss_ref - 1.0), g.fds_ref, g.fds_after, g.threads_ref,
                g.threads_after, g.ok() ? "no growth" : "GROWS");
  }
  std::printf("\n| | count |\n|---|---|\n");
  std::printf("| duration | %.1f min |\n| pc_server restarts | %d |\n| link cuts of robot1 | %d |\n", since(t0) / 60.0,
              restarts, cuts);
  std::printf("| alarm transitions robot1 logged | %zu |\n| in the catalog | %zu (%zu in order, %zu within 100 ms; worst %lld ms) |\n",
              logged.size(), cataloged.size(), in_order, time_ok, static_cast<long long>(worst_ms));
  std::printf("| events the simulated robots sent during their runs | %llu |\n| in the catalog | %lld (%lld distinct) |\n",
              static_cast<unsigned long long>(fleet_events_sent), static_cast<long long>(ev_total),
              static_cast<long long>(ev_distinct));
  std::printf("| simulated robots' runs / telemetry recorded | %d / %llu |\n| telemetry missing / doubled inside runs | %llu / %llu |\n",
              tlm.runs, static_cast<unsigned long long>(tlm.recorded), static_cast<unsigned long long>(tlm.missing),
              static_cast<unsigned long long>(tlm.duplicates));
  if (!samples.empty())
    std::printf("| catalog / MCAP / video on disk at the end | %.2f / %.1f / %.1f MB |\n", samples.back().catalog_mb,
                samples.back().mcap_mb, samples.back().video_mb);
  for (const auto& p : problems) std::printf("problem: %s\n", p.c_str());
  if (!tlm.error.empty()) std::printf("telemetry check: %s\n", tlm.error.c_str());
  std::printf("soak: %s\n", pass ? "PASS" : "FAIL");
  std::fflush(stdout);

  if (!o.json.empty()) {
    nlohmann::json j;
    j["options"] = {{"hours", o.hours}, {"robots", o.robots}, {"hz", o.hz}, {"restart_min", o.restart_min},
                    {"cut_every_s", o.cut_every_s}, {"sample_s", o.sample_s}, {"ref_min", o.ref_min}, {"seed", o.seed}};
    for (const auto& sm : samples)
      j["samples"].push_back({{"t_min", sm.t_min}, {"incarnation", sm.incarnation}, {"server", toJson(sm.server)},
                              {"client", toJson(sm.client)}, {"mcu_sim", toJson(sm.sim)}, {"soak", toJson(sm.self)},
                              {"catalog_mb", sm.catalog_mb}, {"mcap_mb", sm.mcap_mb}, {"video_mb", sm.video_mb},
                              {"alarms_logged", sm.alarms_logged}, {"alarms_cataloged", sm.alarms_cataloged}});
    for (const auto& g : growth)
      j["growth"].push_back({{"process", g.what}, {"judged", g.judged()}, {"rss_ref_mb", g.rss_ref},
                             {"rss_after_mb", g.rss_after}, {"fds_ref", g.fds_ref}, {"fds_after", g.fds_after},
                             {"threads_ref", g.threads_ref}, {"threads_after", g.threads_after}, {"ok", g.ok()}});
    j["restarts"] = restarts;
    j["cuts"] = cuts;
    j["alarms"] = {{"logged", logged.size()}, {"cataloged", cataloged.size()}, {"in_order", in_order},
                   {"within_100ms", time_ok}, {"worst_ms", worst_ms}};
    j["fleet_events"] = {{"sent", fleet_events_sent}, {"cataloged", ev_total}, {"distinct", ev_distinct}};
    j["fleet_telemetry"] = {{"runs", tlm.runs}, {"recorded", tlm.recorded}, {"missing", tlm.missing},
                            {"duplicates", tlm.duplicates}};
    j["problems"] = problems;
    j["pass"] = pass;
    std::ofstream(o.json) << j.dump(1) << "\n";
  }
  if (!pass) std::fprintf(stderr, "%s", s.logs().c_str());
  return pass ? 0 : 1;
}
