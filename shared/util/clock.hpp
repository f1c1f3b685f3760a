#pragma once
// Monotonic time for I/O layers (controllers take time as an argument instead).
#include <chrono>
#include <cstdint>

namespace inspect {

/// CLOCK_MONOTONIC in nanoseconds; comparable across processes on one machine.
inline int64_t monoNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}
inline uint64_t monoNowUs() { return static_cast<uint64_t>(monoNowNs() / 1000); }

/// Seconds as a steady_clock duration (for timers).
inline std::chrono::steady_clock::duration steadyDuration(double seconds) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(seconds));
}

}  // namespace inspect
