// util::LatencyHistogram: quantiles to its 10 us buckets, the exact maximum,
// the missed 100 Hz deadlines, samples beyond its range.
#include "shared/util/latency_histogram.hpp"

#include <gtest/gtest.h>

using inspect::util::LatencyHistogram;

TEST(LatencyHistogram, EmptyIsZero) {
  LatencyHistogram h;
  EXPECT_EQ(h.count(), 0u);
  EXPECT_EQ(h.quantileNs(0.5), 0);
  EXPECT_EQ(h.maxNs(), 0);
}

TEST(LatencyHistogram, QuantilesToTheBucketAndExactMax) {
  LatencyHistogram h;
  // 1..100 us, one each: the median is the 50th sample (50 us, in the
  // bucket [50, 60) us, reported as its upper edge), p99 the 99th.
  for (int us = 1; us <= 100; ++us) h.record(us * 1000);
  EXPECT_EQ(h.count(), 100u);
  EXPECT_EQ(h.quantileNs(0.5), 60'000);
  EXPECT_EQ(h.quantileNs(0.99), 100'000);
  EXPECT_EQ(h.quantileNs(1.0), 100'000);  // never above the maximum
  EXPECT_EQ(h.maxNs(), 100'000);
  EXPECT_EQ(h.overDeadline(), 0u);
}

TEST(LatencyHistogram, DeadlinesAndOverflow) {
  LatencyHistogram h;
  for (int i = 0; i < 98; ++i) h.record(40'000);
  h.record(12'000'000);  // a missed 10 ms deadline
  h.record(80'000'000);  // beyond the 50 ms range
  h.record(-5);          // a clock step backwards counts as 0
  EXPECT_EQ(h.count(), 101u);
  EXPECT_EQ(h.overDeadline(), 2u);
  EXPECT_EQ(h.maxNs(), 80'000'000);
  EXPECT_EQ(h.quantileNs(0.5), 50'000);
  EXPECT_EQ(h.quantileNs(1.0), 80'000'000);
  EXPECT_NE(h.summary("frames").find("101 frames; p50 0.050 ms"), std::string::npos) << h.summary("frames");
  EXPECT_NE(h.summary("frames").find("max 80.000 ms; over 10 ms: 2"), std::string::npos) << h.summary("frames");
}
