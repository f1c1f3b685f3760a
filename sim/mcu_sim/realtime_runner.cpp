#include "sim/mcu_sim/realtime_runner.hpp"

#include <poll.h>
#include <signal.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <vector>

#include "shared/util/clock.hpp"

namespace inspect::sim {
namespace {

volatile std::sig_atomic_t g_stop = 0;
sigset_t g_wait_mask;  // the mask ppoll() waits with: stop signals deliverable
bool g_signals_installed = false;

extern "C" void onStopSignal(int) { g_stop = 1; }

// Upper bound on reads per wake-up so a flooding host cannot stall sim time.
constexpr int kMaxReadsPerWake = 64;

}  // namespace

double SerialStats::txBytesPerSimSecond() const {
  return sim_s > 0.0 ? static_cast<double>(bytes_sent + bytes_dropped) / sim_s : 0.0;
}

double SerialStats::lineUtilisation() const { return txBytesPerSimSecond() / RealtimeRunner::kLineBytesPerS; }

std::string formatSerialStats(const SerialStats& s) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "serial sent=%llu bytes (%.0f B/s of sim time, line utilisation %.1f %% of 11520 B/s) "
                "dropped=%llu frames=%llu received=%llu bytes frames_ok=%llu bad_cobs=%llu bad_crc=%llu "
                "bad_length=%llu unknown_id=%llu overflow=%llu seq_gaps=%llu sim_s=%.3f wall_s=%.3f stalls=%llu "
                "max_stall_ms=%.0f",
                static_cast<unsigned long long>(s.bytes_sent), s.txBytesPerSimSecond(), 100.0 * s.lineUtilisation(),
                static_cast<unsigned long long>(s.bytes_dropped), static_cast<unsigned long long>(s.frames_sent),
                static_cast<unsigned long long>(s.bytes_received), static_cast<unsigned long long>(s.rx.frames_ok),
                static_cast<unsigned long long>(s.rx.bad_cobs), static_cast<unsigned long long>(s.rx.bad_crc),
                static_cast<unsigned long long>(s.rx.bad_length), static_cast<unsigned long long>(s.rx.unknown_id),
                static_cast<unsigned long long>(s.rx.overflow), static_cast<unsigned long long>(s.rx.seq_gaps), s.sim_s,
                s.wall_s, static_cast<unsigned long long>(s.stalls), s.max_stall_ms);
  return buf;
}

void RealtimeRunner::installStopSignals() {
  struct sigaction sa{};
  sa.sa_handler = onStopSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
  sigset_t block;
  sigemptyset(&block);
  sigaddset(&block, SIGINT);
  sigaddset(&block, SIGTERM);
  sigprocmask(SIG_BLOCK, &block, &g_wait_mask);
  sigdelset(&g_wait_mask, SIGINT);
  sigdelset(&g_wait_mask, SIGTERM);
  g_signals_installed = true;
}

RealtimeRunner::RealtimeRunner(Simulation& sim, PtyPort& port, SimObserver* observer, Options opts)
    : sim_(sim), port_(port), observer_(observer), opts_(opts) {}

SerialStats RealtimeRunner::stats(double wall_s) const {
  SerialStats s;
  s.bytes_sent = port_.bytesWritten();
  s.bytes_dropped = port_.bytesDropped();
  s.bytes_received = port_.bytesRead();
  s.frames_sent = sim_.hilMcu() ? sim_.hilMcu()->framesSent() : sim_.mcu().framesSent();
  s.rx = sim_.mcu().rxCounters();
  s.sim_s = sim_.timeS();
  s.wall_s = wall_s;
  s.stalls = stalls_;
  s.max_stall_ms = max_stall_ms_;
  return s;
}

RunSummary RealtimeRunner::run() {
  if (!g_signals_installed) installStopSignals();
  const double rate = opts_.rate;
  const std::optional<uint64_t> end_ms =
      opts_.duration_s ? std::optional<uint64_t>(static_cast<uint64_t>(std::llround(*opts_.duration_s * 1000.0)))
                       : std::nullopt;
  const uint64_t start_ms = sim_.timeMs();
  int64_t t0_ns = monoNowNs();  // moved on by a frozen stall
  std::vector<uint8_t> tx;
  std::array<uint8_t, 4096> rx{};

  // Sim time (ms) that the wall clock has reached.
  auto simNowMs = [&](int64_t now_ns) {
    const double ms = static_cast<double>(now_ns - t0_ns) * rate / 1e6;
    uint64_t t = start_ms + static_cast<uint64_t>(std::max(0.0, std::floor(ms)));
    if (end_ms) t = std::min(t, *end_ms);
    return t;
  };
  auto catchUp = [&] {
    uint64_t target_ms = simNowMs(monoNowNs());
    // Wall time since the first frame still to send was due: beyond a frame
    // period, this process was not run when it should have been.
    const uint64_t kP = sim_.outputPeriodMs();
    const uint64_t due_ms = (sim_.timeMs() + kP - 1) / kP * kP;
    if (target_ms > due_ms + kP) {
      const double late_ms = static_cast<double>(target_ms - due_ms) / rate;
      if (late_ms > kStallReport_ms) {
        ++stalls_;
        max_stall_ms_ = std::max(max_stall_ms_, late_ms);
        std::fprintf(stderr, "mcu_sim: not run for %.0f ms (sim t=%.3f s): the host got no frames meanwhile%s\n",
                     late_ms, static_cast<double>(due_ms) / 1e3, opts_.freeze_on_stall ? "; the world waited" : "");
        if (opts_.freeze_on_stall) {
          // The world resumes where the stall began: the wall clock's
          // origin moves on by the stall, and the frame that was due is next.
          t0_ns += static_cast<int64_t>((static_cast<double>(target_ms - due_ms) / rate) * 1e6);
          target_ms = simNowMs(monoNowNs());
        }
      }
    }
    sim_.advanceTo(target_ms);
    sim_.takeTx(tx);
    if (!tx.empty()) port_.write(tx);
    if (opts_.on_caught_up) opts_.on_caught_up(sim_);
  };

  std::string reason;
  for (;;) {
    if (g_stop) {
      reason = "signal";
      break;
    }
    catchUp();
    if (end_ms && sim_.timeMs() >= *end_ms) {
      reason = "duration";
      break;
    }
    // Wake when the step that emits the next pending frame is due (the frame
    // at t is sent by the step from t to t + 1 ms).
    const uint64_t kP = sim_.outputPeriodMs();
    uint64_t wake_ms = (sim_.timeMs() + kP - 1) / kP * kP + Simulation::kStep_ms;
    // The MCU's watchdog runs every 1 ms step like the firmware's timer
    // interrupt: wake for the step in which it would trip, so that the motors
    // stop at that moment of wall time too, not at the next frame.
    if (const auto wd = sim_.mcu().watchdogDeadlineMs(); wd && *wd >= sim_.timeMs())
      wake_ms = std::min(wake_ms, *wd + Simulation::kStep_ms);
    if (end_ms) wake_ms = std::min(wake_ms, *end_ms);
    const int64_t wake_ns =
        t0_ns + static_cast<int64_t>(std::ceil(static_cast<double>(wake_ms - start_ms) * 1e6 / rate)) + 1;
    const int64_t wait_ns = std::max<int64_t>(0, wake_ns - monoNowNs());
    timespec ts{static_cast<time_t>(wait_ns / 1000000000), static_cast<long>(wait_ns % 1000000000)};
    pollfd pfd{port_.fd(), POLLIN, 0};
    const int r = ppoll(&pfd, 1, &ts, &g_wait_mask);
    if (r > 0 && (pfd.revents & POLLIN)) {
      for (int i = 0; i < kMaxReadsPerWake; ++i) {
        const std::size_t n = port_.read(rx);
        if (n == 0) break;
        // The bytes belong to the current sim time, taken after the read: they
        // had all arrived by then. (Before it, a process not run between the
        // two stamped a whole backlog of the HIL board's reports with a time
        // they were sent after, and its clock estimate ran up to 280 ms ahead.)
        catchUp();
        sim_.receive({rx.data(), n});
      }
    } else if (r > 0) {
      // Hang-up or error without data (cannot happen while we hold the slave
      // open): wait out the deadline instead of spinning.
      ppoll(nullptr, 0, &ts, &g_wait_mask);
    }
  }
  const double wall_s = static_cast<double>(monoNowNs() - t0_ns) / 1e9;
  if (observer_) observer_->onEvent(sim_.timeS(), "stop", reason);
  return {sim_.state().pose, stats(wall_s), reason};
}

}  // namespace inspect::sim
