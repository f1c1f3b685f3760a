// util::TokenBucket: a pure function of the times it is given.
#include <gtest/gtest.h>

#include "shared/util/token_bucket.hpp"

using inspect::util::TokenBucket;

TEST(TokenBucket, StartsFullTakesAndRefillsAtItsRateUpToItsDepth) {
  TokenBucket b(100.0, 10.0);  // 100/s, 10 deep
  for (int i = 0; i < 10; ++i) EXPECT_TRUE(b.take(1, 5.0)) << i;
  EXPECT_FALSE(b.take(1, 5.0));       // empty
  EXPECT_FALSE(b.take(2, 5.015));     // 1.5 tokens back
  EXPECT_TRUE(b.take(1, 5.015));
  EXPECT_NEAR(b.tokens(5.015), 0.5, 1e-9);
  EXPECT_NEAR(b.tokens(100.0), 10.0, 1e-9);  // never past its depth
  EXPECT_FALSE(b.take(11, 100.0));    // more than it can hold: never, and nothing taken
  EXPECT_NEAR(b.tokens(100.0), 10.0, 1e-9);
  EXPECT_NEAR(b.tokens(99.0), 10.0, 1e-9);   // a time going back adds nothing
}

TEST(TokenBucket, ASteadyRateAboveTheLimitPassesTheLimitOnly) {
  TokenBucket b(2000.0, 2000.0);
  int passed = 0;
  for (int i = 0; i < 20000; ++i) passed += b.take(1, i * 1e-4);  // 10000/s for 2 s
  EXPECT_NEAR(passed, 2000 + 2 * 2000, 5);  // the burst, then the rate
}
