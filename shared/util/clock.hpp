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

/// The system (wall) clock in nanoseconds since the Unix epoch: the time base
/// of recordings (MCAP log times) and of the Foxglove live view.
inline uint64_t wallNowNs() {
  return static_cast<uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
          .count());
}

/// A time on this process's monotonic clock (us, in the past) as wall-clock ns.
inline uint64_t monoUsToWallNs(uint64_t mono_us) {
  const int64_t age_ns = (static_cast<int64_t>(monoNowUs()) - static_cast<int64_t>(mono_us)) * 1000;
  return wallNowNs() - static_cast<uint64_t>(age_ns > 0 ? age_ns : 0);
}

/// Seconds as a steady_clock duration (for timers).
inline std::chrono::steady_clock::duration steadyDuration(double seconds) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(seconds));
}

}  // namespace inspect
