// The Foxglove bridge's per-client request rate, on times given by the test.
#include <gtest/gtest.h>

#include "pc_server/foxglove/ws_rate_limit.hpp"

using namespace inspect::server::foxglove;
using V = RequestRateLimit::Verdict;

TEST(RequestRateLimit, TwoSecondsOfBurstThenTheRateAndOneNoticeASecond) {
  RequestRateLimit r(100);
  for (int i = 0; i < 200; ++i) ASSERT_EQ(r.take(10.0), V::kAllowed) << i;  // the 2 s burst
  EXPECT_EQ(r.take(10.0), V::kRefusedTell);
  EXPECT_EQ(r.take(10.0), V::kRefusedQuiet) << "told already: only counted";
  for (int i = 0; i < 50; ++i) ASSERT_EQ(r.take(10.5), V::kAllowed) << i;  // 0.5 s at 100/s
  EXPECT_EQ(r.take(10.5), V::kRefusedQuiet) << "told 0.5 s ago";
  for (int i = 0; i < 109; ++i) ASSERT_EQ(r.take(11.6), V::kAllowed) << i;  // 1.1 s more (110, less rounding)
  V next = V::kAllowed;
  for (int i = 0; i < 3 && next == V::kAllowed; ++i) next = r.take(11.6);
  EXPECT_EQ(next, V::kRefusedTell) << "more than a second since the last notice";
  EXPECT_DOUBLE_EQ(r.perSecond(), 100);
}
