#pragma once
// Durations of a real-time loop (robot_client: sensor frame in -> wheel
// command out) counted in fixed buckets: recording is a few additions, never
// an allocation, so it can run in the 100 Hz tick for hours. Quantiles come
// out to the bucket's resolution (10 us up to 50 ms); the maximum is exact.
#include <array>
#include <cstdint>
#include <string>

namespace inspect::util {

class LatencyHistogram {
 public:
  static constexpr int64_t kBucketNs = 10'000;                // 10 us
  static constexpr std::size_t kBuckets = 5'000;              // up to 50 ms
  static constexpr int64_t kDeadlineNs = 10'000'000;          // one 100 Hz period

  void record(int64_t ns);
  uint64_t count() const { return count_; }
  /// Samples over `kDeadlineNs` (a missed 100 Hz deadline).
  uint64_t overDeadline() const { return over_deadline_; }
  int64_t maxNs() const { return max_ns_; }
  /// The q-quantile (0..1) in ns: the upper edge of the bucket holding it;
  /// beyond the last bucket, the maximum. 0 when empty.
  int64_t quantileNs(double q) const;
  /// "N frames; p50 X ms, p99 Y ms, max Z ms; over 10 ms: K".
  std::string summary(const std::string& what) const;

 private:
  std::array<uint32_t, kBuckets> buckets_{};
  uint64_t overflow_ = 0;
  uint64_t count_ = 0;
  uint64_t over_deadline_ = 0;
  int64_t max_ns_ = 0;
};

}  // namespace inspect::util
