// bench_firmware: the firmware's real-time figures in QEMU, hardware in the
// loop (docs/firmware.md "Measured"): the QEMU board's image under
// scripts/mcu_qemu.sh with mcu_sim --hil in the square room, driven as
// robot_client drives it (the robot turning in place, commands every 20 ms,
// a heartbeat every 100 ms). Measures
//   - the sensor frames' rate on the host's clock and on the MCU's, against
//     the protocol's 100 Hz (target: within 1 % over 10 minutes), frames lost
//     (sequence gaps, bad frames, after a 1 s warm-up: the line opened in the
//     middle of a frame may cut the first) and the longest gap between two;
//   - the control period's jitter: how late each 1 ms tick started on TIM2
//     (the board's reports over the HIL link; target p99 under 1 ms);
//   - the watchdog: commands stopped N times; from the first frame echoing the
//     last command (applied within the 10 ms before it) to the first frame
//     flagging WATCHDOG, on the MCU's clock: 190-210 ms when the watchdog trips
//     200 ms after the command (target: 200 ms + one 10 ms period).
// Prints a table; --json FILE writes the same figures.
// QEMU and mcu_sim run SCHED_FIFO at --realtime-priority (default 20, as in the
// stack tests and the demo: the MCU is a chip of its own; 0 = normal).
// --cpu N: QEMU on CPU N alone, mcu_sim and the bench on the others (mcu_qemu.sh --cpu).
//   bench_firmware [--seconds S] [--watchdog-trials N] [--elf FILE] [--realtime-priority N] [--cpu N] [--json FILE]
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "shared/util/cli_args.hpp"
#include "tests/firmware/qemu_board.hpp"
#include "tests/support/paths.hpp"
#include "tests/support/process.hpp"

using namespace inspect;
using Json = nlohmann::json;

namespace {

struct Figures {
  double seconds = 0;
  std::size_t frames = 0;
  double host_hz = 0, mcu_hz = 0;
  uint64_t seq_gaps = 0, bad_frames = 0;
  double max_gap_ms = 0;
  double jitter_p50_ms = -1, jitter_p99_ms = -1, jitter_max_ms = -1;
  uint64_t ticks_reported = 0;
  std::vector<double> watchdog_ms;  // per trial, MCU clock
};

// "... N firmware control ticks late (TIM2); p50 X ms, p99 Y ms, max Z ms; ..." from mcu_sim's summary.
void parseJitter(const std::string& out, Figures& f) {
  const auto at = out.find("hil frames_in=");
  if (at == std::string::npos) return;
  const auto semi = out.find("; ", at);
  unsigned long long n = 0;
  if (semi == std::string::npos ||
      std::sscanf(out.c_str() + semi + 2, "%llu firmware control ticks late (TIM2); p50 %lf ms, p99 %lf ms, max %lf ms", &n,
                  &f.jitter_p50_ms, &f.jitter_p99_ms, &f.jitter_max_ms) != 4) {
    return;
  }
  f.ticks_reported = n;
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 600;
  int trials = 10;
  int priority = 20;
  std::string elf, json_path, cpu;
  cli::readOrExit("bench_firmware", argc, argv, [&](cli::ArgReader& a) {
    if (a.isHelp()) {
      std::printf("usage: bench_firmware [--seconds S] [--watchdog-trials N] [--elf FILE] [--realtime-priority N] [--cpu N]\n"
                  "                      [--json FILE]\n"
                  "The firmware in QEMU with mcu_sim --hil: frame rate (host and MCU clock), the control\n"
                  "tick's lateness on TIM2, the watchdog's trip time. Default 600 s, 10 trials, the image\n"
                  "build-firmware/inspect-mcu-qemu.elf, QEMU and mcu_sim at SCHED_FIFO 20 (docs/firmware.md).\n"
                  "--cpu N: QEMU on CPU N alone, mcu_sim on the others (scripts/mcu_qemu.sh --cpu).\n");
      std::exit(0);
    } else if (a.is("--seconds")) seconds = a.numberAbove(1.0, 86400.0);
    else if (a.is("--watchdog-trials")) trials = static_cast<int>(a.integer(1, 1000));
    else if (a.is("--elf")) elf = a.path();
    else if (a.is("--realtime-priority")) priority = static_cast<int>(a.integer(0, 99));
    else if (a.is("--cpu")) cpu = std::to_string(a.integer(0, 1023));
    else if (a.is("--json")) json_path = a.path();
    else a.unknown();
  });
  if (elf.empty()) elf = test::srcPath("build-firmware/inspect-mcu-qemu.elf");
  if (!test::exists(elf)) {
    std::fprintf(stderr, "bench_firmware: no image at %s (scripts/build_firmware.sh, or --elf)\n", elf.c_str());
    return 2;
  }
  test::TempDir dir("bench_firmware");
  Figures f;
  f.seconds = seconds;
  std::string out;
  try {
    // QEMU and its mcu_sim at that priority (scripts/mcu_qemu.sh passes it on).
    std::vector<std::string> args{"--realtime-priority", std::to_string(priority)};
    if (!cpu.empty()) args.insert(args.end(), {"--cpu", cpu});
    args.insert(args.end(), {"--mcu-sim", test::binPath("mcu_sim"), "--world", test::srcPath("config/worlds/square_room.yaml"),
                             "--robot", test::srcPath("config/robot.yaml")});
    test::QemuBoard board(elf, dir.path(), args);
    auto& frames = board.frames();
    board.drive(1.0, -500, 500);  // the link up, the loop settled
    frames.clear();
    // Counted from here: opened in the middle of a frame, the line may cut the first one.
    const uint64_t gaps_before = board.counters().seq_gaps, errors_before = board.counters().errors();
    // The rate: turning in place, as long as asked.
    board.drive(seconds, -1000, 1000);
    f.frames = frames.size();
    if (frames.size() > 1) {
      const double host_s = static_cast<double>(frames.back().host_ns - frames.front().host_ns) / 1e9;
      const double mcu_s = (frames.back().frame.mcu_time_ms - frames.front().frame.mcu_time_ms) / 1000.0;
      f.host_hz = static_cast<double>(frames.size() - 1) / host_s;
      f.mcu_hz = static_cast<double>(frames.size() - 1) / mcu_s;
      for (std::size_t i = 1; i < frames.size(); ++i)
        f.max_gap_ms = std::max(f.max_gap_ms, static_cast<double>(frames[i].host_ns - frames[i - 1].host_ns) / 1e6);
    }
    f.seq_gaps = board.counters().seq_gaps - gaps_before;
    f.bad_frames = board.counters().errors() - errors_before;
    // The watchdog: the last command's application is the first frame echoing
    // its seq (applied within the 10 ms before it); the trip, the first frame flagging it.
    for (int t = 0; t < trials; ++t) {
      frames.clear();
      board.drive(0.5, -1000, 1000);
      const uint8_t last = static_cast<uint8_t>(board.nextWheelSeq() - 1);
      const std::size_t sent_at = frames.size();  // the last command's echo may come during drive()'s last pump
      board.pump(0.4);
      for (int i = 0; i < 5; ++i) board.send(serial::Heartbeat{0}), board.pump(0.02);
      int64_t applied = -1, tripped = -1;
      for (std::size_t i = sent_at > 3 ? sent_at - 3 : 0; i < frames.size(); ++i) {
        const auto& r = frames[i];
        if (applied < 0 && r.frame.cmd_seq_echo == last) applied = r.frame.mcu_time_ms;
        if (applied >= 0 && tripped < 0 && (r.frame.faults & serial::kFaultWatchdog)) tripped = r.frame.mcu_time_ms;
      }
      if (applied >= 0 && tripped >= 0) f.watchdog_ms.push_back(static_cast<double>(tripped - applied));
    }
    out = board.stop(10.0);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_firmware: %s\n", e.what());
    return 1;
  }
  parseJitter(out, f);
  std::sort(f.watchdog_ms.begin(), f.watchdog_ms.end());
  const double wd_max = f.watchdog_ms.empty() ? -1 : f.watchdog_ms.back();
  const double wd_min = f.watchdog_ms.empty() ? -1 : f.watchdog_ms.front();
  const double rate_err = f.host_hz > 0 ? 100.0 * std::abs(f.host_hz - 100.0) / 100.0 : 100.0;

  std::printf("\nThe firmware in QEMU, hardware in the loop (mcu_sim --hil, square room), %.0f s, SCHED_FIFO %d\n\n",
              seconds, priority);
  std::printf("| figure | value | target | met |\n|---|---|---|---|\n");
  std::printf("| sensor frames, host clock | %.3f Hz (%zu frames) | 100 Hz within 1 %% | %s |\n", f.host_hz, f.frames,
              rate_err <= 1.0 ? "yes" : "NO");
  std::printf("| sensor frames, MCU clock (TIM2) | %.3f Hz | 100 Hz | %s |\n", f.mcu_hz,
              std::abs(f.mcu_hz - 100.0) <= 1.0 ? "yes" : "NO");
  std::printf("| frames lost (sequence gaps) / bad | %llu / %llu | 0 | %s |\n", static_cast<unsigned long long>(f.seq_gaps),
              static_cast<unsigned long long>(f.bad_frames), f.seq_gaps + f.bad_frames == 0 ? "yes" : "NO");
  std::printf("| longest gap between frames (host) | %.1f ms | | |\n", f.max_gap_ms);
  std::printf("| control tick late on TIM2, p50 / p99 / max | %.3f / %.3f / %.3f ms (%llu ticks) | p99 < 1 ms | %s |\n",
              f.jitter_p50_ms, f.jitter_p99_ms, f.jitter_max_ms, static_cast<unsigned long long>(f.ticks_reported),
              f.jitter_p99_ms >= 0 && f.jitter_p99_ms < 1.0 ? "yes" : "NO");
  std::printf("| watchdog: last command applied -> WATCHDOG, min / max | %.0f / %.0f ms (%zu trials) | <= 210 ms | %s |\n",
              wd_min, wd_max, f.watchdog_ms.size(), wd_max >= 0 && wd_max <= 210 ? "yes" : "NO");
  if (!json_path.empty()) {
    Json j = {{"seconds", f.seconds},        {"realtime_priority", priority},        {"frames", f.frames},           {"host_hz", f.host_hz},
              {"mcu_hz", f.mcu_hz},          {"seq_gaps", f.seq_gaps},       {"bad_frames", f.bad_frames},
              {"max_gap_ms", f.max_gap_ms},  {"jitter_p50_ms", f.jitter_p50_ms}, {"jitter_p99_ms", f.jitter_p99_ms},
              {"jitter_max_ms", f.jitter_max_ms}, {"ticks_reported", f.ticks_reported},
              {"watchdog_ms", f.watchdog_ms}};
    std::ofstream(json_path) << j.dump(2) << "\n";
  }
  return 0;
}
