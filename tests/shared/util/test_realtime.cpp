// util::enterRealtime: the calling thread only, reset-on-fork for what it
// starts afterwards, and a reason instead of an error when not permitted.
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <thread>

#include "shared/util/realtime.hpp"

using inspect::util::enterRealtime;

TEST(Realtime, ZeroLeavesTheThreadAloneAndOutOfRangeIsRefused) {
  EXPECT_EQ(enterRealtime(0), "");
  EXPECT_EQ(sched_getscheduler(0) & ~SCHED_RESET_ON_FORK, SCHED_OTHER);
  EXPECT_NE(enterRealtime(100).find("above 99"), std::string::npos);
}

TEST(Realtime, OnlyTheCallingThreadAndNothingItStartsAfterwards) {
  // On a thread of its own, so the test program's main thread stays ordinary.
  std::string why;
  int policy = -1, child_policy = -1, main_policy = sched_getscheduler(0);
  std::thread t([&] {
    why = enterRealtime(5);
    policy = sched_getscheduler(0);
    std::thread c([&] { child_policy = sched_getscheduler(0); });
    c.join();
  });
  t.join();
  if (!why.empty()) {
    EXPECT_NE(why.find("not permitted"), std::string::npos) << why;
    GTEST_SKIP() << "no privilege for SCHED_FIFO here: " << why;
  }
  EXPECT_EQ(policy, SCHED_FIFO | SCHED_RESET_ON_FORK);
  EXPECT_EQ(child_policy, SCHED_OTHER) << "a thread started by the real-time loop must be ordinary";
  EXPECT_EQ(sched_getscheduler(0), main_policy) << "another thread's scheduling changed";
}
