#include "shared/util/latency_histogram.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace inspect::util {

void LatencyHistogram::record(int64_t ns) {
  ns = std::max<int64_t>(ns, 0);
  const auto b = static_cast<std::size_t>(ns / kBucketNs);
  if (b < kBuckets)
    ++buckets_[b];
  else
    ++overflow_;
  ++count_;
  if (ns > kDeadlineNs) ++over_deadline_;
  max_ns_ = std::max(max_ns_, ns);
}

int64_t LatencyHistogram::quantileNs(double q) const {
  if (count_ == 0) return 0;
  q = std::clamp(q, 0.0, 1.0);
  // The rank of the sample (1-based) that the quantile falls on.
  const auto rank = std::max<uint64_t>(1, static_cast<uint64_t>(std::ceil(q * static_cast<double>(count_))));
  uint64_t seen = 0;
  for (std::size_t b = 0; b < kBuckets; ++b) {
    seen += buckets_[b];
    if (seen >= rank) return std::min(static_cast<int64_t>(b + 1) * kBucketNs, max_ns_);
  }
  return max_ns_;
}

std::string LatencyHistogram::summary(const std::string& what) const {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%llu %s; p50 %.3f ms, p99 %.3f ms, max %.3f ms; over %.0f ms: %llu",
                static_cast<unsigned long long>(count_), what.c_str(), static_cast<double>(quantileNs(0.5)) * 1e-6,
                static_cast<double>(quantileNs(0.99)) * 1e-6, static_cast<double>(max_ns_) * 1e-6,
                static_cast<double>(kDeadlineNs) * 1e-6, static_cast<unsigned long long>(over_deadline_));
  return buf;
}

}  // namespace inspect::util
