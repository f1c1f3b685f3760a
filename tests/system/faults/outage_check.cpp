// outage_check: nothing lost across outages (store-and-forward, issue 38,
// docs/store-and-forward.md), through the real programs.
//
// pc_server records a run while robot_client (with its event journal)
// reaches it through tcp_fault_relay. The robot stands in a world made for
// the check: a CH4 leak beside it that pulses on and off and two gas sensors
// that drop out on a schedule, so that alarms are raised and cleared all
// along. The link is cut N times for 0.5-5 s (bytes in flight lost, new
// connections refused), and K of those times robot_client is SIGKILLed in
// the middle of the cut and started again on its journal. At the end every
// alarm transition robot_client logged must be in the run's MCAP and in the
// catalog exactly once, in order, at the robot's time (within 100 ms).
//
//   outage_check [--cuts N] [--kills K] [--min-cut S] [--max-cut S] [--seed N] [--json FILE]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "shared/util/cli_args.hpp"
#include "tests/support/stack.hpp"
#include "tests/system/faults/gas_outage_world.hpp"

using namespace inspect;
using namespace inspect::test;

namespace {

struct Options {
  int cuts = 100;
  int kills = 10;
  double min_cut_s = 0.5, max_cut_s = 5.0;
  double min_up_s = 1.0, max_up_s = 3.0;
  unsigned seed = 1;
  std::string json;
};

struct Step {
  double up_s, cut_s;
  bool kill;
};

// From each `flow` of the relay to the next connection it accepted (the
// robot's reconnect after the outage), ms; from its output lines
// "tcp_fault_relay: <what> at mono_ns=<ns>".
std::vector<double> reconnectMs(const std::string& relay_out) {
  std::vector<double> out;
  std::istringstream in(relay_out);
  int64_t flow_ns = -1;
  for (std::string line; std::getline(in, line);) {
    const auto at = line.find(" at mono_ns=");
    if (at == std::string::npos) continue;
    const int64_t ns = std::stoll(line.substr(at + 12));
    if (line.find(": flow at") != std::string::npos) flow_ns = ns;
    else if (flow_ns >= 0 && line.find(" accepted at") != std::string::npos) {
      out.push_back(static_cast<double>(ns - flow_ns) * 1e-6);
      flow_ns = -1;
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

void control(const std::string& fifo, const std::string& cmd) {
  std::ofstream(fifo) << cmd << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  cli::readOrExit("outage_check", argc, argv, [&](cli::ArgReader& a) {
    if (a.isHelp()) {
      std::puts("usage: outage_check [--cuts N] [--kills K] [--min-cut S] [--max-cut S] [--seed N] [--json FILE]");
      std::exit(0);
    } else if (a.is("--cuts")) o.cuts = static_cast<int>(a.integer(1, 10000));
    else if (a.is("--kills")) o.kills = static_cast<int>(a.integer(0, 1000));
    else if (a.is("--min-cut")) o.min_cut_s = a.number(0.05, 600);
    else if (a.is("--max-cut")) o.max_cut_s = a.number(0.05, 600);
    else if (a.is("--seed")) o.seed = static_cast<unsigned>(a.integer(0, 1 << 30));
    else if (a.is("--json")) o.json = a.path();
    else a.unknown();
  });
  if (o.max_cut_s < o.min_cut_s) o.max_cut_s = o.min_cut_s;
  o.kills = std::min(o.kills, o.cuts);

  // The schedule, fixed by the seed: up, then cut (a SIGKILL in the middle of every cuts/kills-th).
  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> up(o.min_up_s, o.max_up_s), cut(o.min_cut_s, o.max_cut_s);
  std::vector<Step> plan;
  double planned_s = 0;
  for (int i = 0; i < o.cuts; ++i) {
    const bool kill = o.kills > 0 && i % std::max(1, o.cuts / o.kills) == o.cuts / o.kills / 2 &&
                      std::count_if(plan.begin(), plan.end(), [](const Step& s) { return s.kill; }) < o.kills;
    plan.push_back({up(rng), cut(rng), kill});
    planned_s += plan.back().up_s + plan.back().cut_s + (kill ? 1.0 : 0.0);
  }

  Stack s("outage");
  writeFile(s.dir() / "gas_outages.yaml", gasOutageWorldYaml(planned_s + 120));
  const std::string journal = s.dir() / "robot1-events.journal";
  std::string script =
      "expect robots >= 1 within 20\nexpect sensor_hz > 50 within 5\nrecord start outages\n"
      "wait " + std::to_string(static_cast<int>(planned_s + 5)) + "\n"
      "expect connected == 1 within 30\nwait 3\nrecord stop\nalarms all\n";
  if (!s.startServer(script)) {
    std::fprintf(stderr, "outage_check: pc_server did not start\n%s", s.logs().c_str());
    return 1;
  }
  const std::string fifo = s.dir() / "relay.ctl";
  Process relay = Process::spawn({binPath("tcp_fault_relay"), "--target", "127.0.0.1:" + std::to_string(s.port()),
                                  "--control", fifo, "--port-file", s.dir() / "relay.port"},
                                 s.dir() / "relay.out", s.dir() / "relay.err");
  if (!waitUntil([&] { return exists(s.dir() / "relay.port"); }, 10)) {
    std::fprintf(stderr, "outage_check: tcp_fault_relay did not start\n");
    return 1;
  }
  const int relay_port = std::atoi(readFile(s.dir() / "relay.port").c_str());
  auto& robot = s.startRobot("robot1", s.dir() / "gas_outages.yaml", {}, {},
                             {"--server", "127.0.0.1:" + std::to_string(relay_port), "--journal", journal});
  if (!waitUntil([&] { return s.serverOutput().find("robot1: recording run ") != std::string::npos; }, 40)) {
    std::fprintf(stderr, "outage_check: the run did not start\n%s", s.logs().c_str());
    return 1;
  }
  const auto t0 = std::chrono::steady_clock::now();
  std::printf("outage_check: %d cuts of %.1f-%.1f s, %d robot_client SIGKILLs mid-outage, ~%.0f s\n", o.cuts,
              o.min_cut_s, o.max_cut_s, o.kills, planned_s);
  std::fflush(stdout);
  int kills_done = 0;
  const auto sleepS = [](double sec) { std::this_thread::sleep_for(std::chrono::duration<double>(sec)); };
  for (std::size_t i = 0; i < plan.size(); ++i) {
    sleepS(plan[i].up_s);
    control(fifo, "cut");
    if (plan[i].kill) {
      sleepS(plan[i].cut_s / 2);
      robot.client.signal(SIGKILL);
      robot.client.wait(5);
      s.restartClient("robot1");
      ++kills_done;
      sleepS(plan[i].cut_s / 2 + 1.0);
    } else {
      sleepS(plan[i].cut_s);
    }
    control(fifo, "flow");
    if ((i + 1) % 10 == 0) {
      std::printf("  %zu cuts, %d kills, %.0f s\n", i + 1, kills_done,
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      std::fflush(stdout);
    }
  }
  const auto rc = s.server().wait(planned_s + 120);
  relay.terminate();
  const std::string out = s.serverOutput();
  const std::string tag = "robot1: recording run ";
  const auto at = out.find(tag);
  const std::string run_id = out.substr(at + tag.size(), out.find('\n', at) - at - tag.size());

  // The robot's log (every process's, appended across the restarts) against
  // the run, up to the run's end (`record stop`): the gas world goes on, and a
  // transition the robot logs after the run ended belongs to no run (one at
  // the same instant as the server's exit made a clean run fail here).
  auto logged = robotLoggedAlarms(s.dir() / "robot1-client.err");
  const auto run_end = catalogRunEndUnix(s.dir() / "runs/catalog.sqlite", run_id);
  std::size_t after_run = 0;
  if (run_end) {
    const int64_t end_ms = msOfDayLocal(static_cast<uint64_t>(*run_end * 1e9));
    after_run = static_cast<std::size_t>(
        std::erase_if(logged, [&](const LoggedAlarm& a) { return dayDiffMs(a.ms_of_day, end_ms) > 0; }));
  }
  const std::string run_dir = s.dir() / ("runs/" + run_id);
  std::vector<RecordedAlarm> recorded;
  std::string mcap_error;
  try {
    recorded = mcapAlarms(run_dir + "/run.mcap");
  } catch (const std::exception& e) {
    mcap_error = e.what();
  }
  const auto cataloged = catalogAlarms(s.dir() / "runs/catalog.sqlite", "run_id", run_id);

  // Exactly once, in order: the i-th logged transition is the i-th recorded one.
  std::size_t same = 0, time_ok = 0, cat_time_ok = 0;
  int64_t worst_ms = 0, worst_cat_ms = 0;
  for (std::size_t i = 0; i < std::min(logged.size(), recorded.size()); ++i) {
    if (logged[i].kind != recorded[i].kind || logged[i].text != recorded[i].text) break;
    ++same;
    const int64_t d = std::abs(dayDiffMs(msOfDayLocal(recorded[i].log_ns), logged[i].ms_of_day));
    worst_ms = std::max(worst_ms, d);
    time_ok += d <= 100;
  }
  for (std::size_t i = 0; i < std::min(logged.size(), cataloged.size()); ++i) {
    const int64_t d = std::abs(dayDiffMs(msOfDayLocal(static_cast<uint64_t>(cataloged[i].time_unix * 1e9)),
                                         logged[i].ms_of_day));
    worst_cat_ms = std::max(worst_cat_ms, d);
    cat_time_ok += d <= 100;
  }
  const bool pass = rc && *rc == 0 && mcap_error.empty() && !logged.empty() && same == logged.size() &&
                    recorded.size() == logged.size() && cataloged.size() == logged.size() &&
                    time_ok == logged.size() && cat_time_ok == logged.size() && kills_done == o.kills;

  std::printf("\n| | count |\n|---|---|\n");
  std::printf("| link cuts | %d |\n| robot_client SIGKILLs mid-outage | %d |\n", o.cuts, kills_done);
  std::printf("| alarm transitions robot_client logged during the run | %zu |\n", logged.size());
  std::printf("| ... and after the run's end (in no run) | %zu |\n", after_run);
  std::printf("| in the run's MCAP (/event) | %zu (%zu in order and equal) |\n", recorded.size(), same);
  const auto late = std::count_if(recorded.begin(), recorded.end(), [](const RecordedAlarm& r) { return r.late; });
  std::printf("| of those, stored during an outage and filed after it | %zu |\n", static_cast<std::size_t>(late));
  std::printf("| in the catalog (alarms of run %s) | %zu |\n", run_id.c_str(), cataloged.size());
  std::printf("| MCAP time within 100 ms of the robot's | %zu (worst %lld ms) |\n", time_ok,
              static_cast<long long>(worst_ms));
  std::printf("| catalog time within 100 ms of the robot's | %zu (worst %lld ms) |\n", cat_time_ok,
              static_cast<long long>(worst_cat_ms));
  const auto rec_ms = reconnectMs(readFile(s.dir() / "relay.out"));
  if (!rec_ms.empty())
    std::printf("| reconnect after the link came back, ms (p50 / max of %zu) | %.0f / %.0f |\n", rec_ms.size(),
                rec_ms[rec_ms.size() / 2], rec_ms.back());
  std::printf("| duration | %.0f s |\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  if (!mcap_error.empty()) std::printf("MCAP: %s\n", mcap_error.c_str());
  if (!rc || *rc != 0) std::printf("pc_server's script: %s\n", rc ? "an expect failed" : "did not finish");
  if (same < logged.size() && same < recorded.size())
    std::printf("first difference at %zu: logged %s '%s', recorded %s '%s'\n", same, logged[same].kind.c_str(),
                logged[same].text.c_str(), recorded[same].kind.c_str(), recorded[same].text.c_str());
  std::printf("outage_check: %s\n", pass ? "PASS" : "FAIL");
  if (!o.json.empty()) {
    std::ofstream j(o.json);
    const auto late_n = std::count_if(recorded.begin(), recorded.end(), [](const RecordedAlarm& r) { return r.late; });
    j << "{\"cuts\": " << o.cuts << ", \"kills\": " << kills_done << ", \"logged\": " << logged.size()
      << ", \"mcap\": " << recorded.size() << ", \"mcap_in_order\": " << same << ", \"late\": " << late_n << ", \"catalog\": " << cataloged.size()
      << ", \"mcap_worst_ms\": " << worst_ms << ", \"catalog_worst_ms\": " << worst_cat_ms
      << ", \"pass\": " << (pass ? "true" : "false") << "}\n";
  }
  if (!pass) std::fprintf(stderr, "%s", s.logs().c_str());
  return pass ? 0 : 1;
}
