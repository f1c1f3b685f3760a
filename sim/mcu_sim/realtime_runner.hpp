#pragma once
// Runs a Simulation against the wall clock (optionally faster) and moves bytes
// between it and the pty: one thread, ppoll() on the pty master with the next
// frame's deadline as timeout, no busy-waiting. Stops on SIGINT/SIGTERM or
// after the requested sim duration.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "shared/control/diff_drive.hpp"
#include "shared/serial/frame_codec.hpp"
#include "sim/mcu_sim/pty_port.hpp"
#include "sim/sim_observer.hpp"
#include "sim/simulation.hpp"

namespace inspect::sim {

/// Serial line statistics of one run.
struct SerialStats {
  uint64_t bytes_sent = 0;
  uint64_t bytes_dropped = 0;  // frames nobody read (pty buffer full)
  uint64_t bytes_received = 0;
  uint64_t frames_sent = 0;
  serial::DecoderCounters rx;  // host -> MCU decoder
  double sim_s = 0.0;
  double wall_s = 0.0;
  /// Times this process caught up with the wall clock more than
  /// kStallReport_ms late (it was not run: a loaded or stalled host), and the
  /// worst such delay; the host saw no frames for that long.
  uint64_t stalls = 0;
  double max_stall_ms = 0.0;
  /// Bytes the MCU produced per second of sim time (= per second on a real line).
  double txBytesPerSimSecond() const;
  /// Share of the 115200 8N1 line (11520 bytes/s) the MCU -> host traffic uses.
  double lineUtilisation() const;
};

/// One-line summary of the statistics ("serial sent=... utilisation=...").
std::string formatSerialStats(const SerialStats& s);

/// How a run ended.
struct RunSummary {
  control::Pose2 final_pose;
  SerialStats stats;
  std::string stop_reason;  // "signal" or "duration"
};

/// Lock-step real-time driver.
class RealtimeRunner {
 public:
  /// Bytes per second of a 115200 baud 8N1 line.
  static constexpr double kLineBytesPerS = 11520.0;
  /// A catch-up this much later than the frame it sends (wall ms) is a stall:
  /// counted, and logged on stderr with its length.
  static constexpr double kStallReport_ms = 30.0;

  struct Options {
    double rate = 1.0;                 // sim seconds per wall second
    std::optional<double> duration_s;  // sim seconds; empty: until a stop signal
    /// Called on the runner's thread each time the simulation has caught up
    /// with the wall clock (mcu_sim's camera takes its snapshot there); must
    /// be quick. Empty: none.
    std::function<void(const Simulation&)> on_caught_up;
    /// A stall (a catch-up more than kStallReport_ms late) pauses the
    /// simulated world for its length instead of simulating it in one step
    /// with the last wheel commands and no frames out (mcu_sim --freeze-on-stall).
    bool freeze_on_stall = false;
  };

  /// Blocks SIGINT/SIGTERM and installs handlers that only set a flag; the
  /// signals are then delivered only inside ppoll(), so none is missed. Call
  /// early in main(), before resources that need cleaning up are made.
  static void installStopSignals();

  RealtimeRunner(Simulation& sim, PtyPort& port, SimObserver* observer, Options opts);
  /// Runs until a stop signal or the duration; logs the `stop` event.
  RunSummary run();

 private:
  SerialStats stats(double wall_s) const;
  uint64_t stalls_ = 0;
  double max_stall_ms_ = 0.0;
  Simulation& sim_;
  PtyPort& port_;
  SimObserver* observer_;
  Options opts_;
};

}  // namespace inspect::sim
