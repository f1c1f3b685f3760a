// A Foxglove client's send queue (pc_server/foxglove/send_queue): lanes in
// priority order, the oldest data dropped past its budget, video skipping to
// the next keyframe, control refused (the caller closes) past its limit.
#include <gtest/gtest.h>

#include "pc_server/foxglove/send_queue.hpp"

using namespace inspect::server::foxglove;

namespace {
OutMessage msg(const std::string& text, std::size_t pad = 0) { return {text + std::string(pad, '.'), nullptr, false}; }
std::string popHead(SendQueue& q) {
  auto m = q.pop();
  return m ? m->head.substr(0, m->head.find('.')) : "";
}
}  // namespace

TEST(SendQueue, ControlBeforeDataBeforeVideo) {
  SendQueue q;
  q.pushVideo(1, true, msg("key"));
  q.pushData(msg("telemetry"));
  ASSERT_TRUE(q.pushControl(msg("advertise")));
  EXPECT_EQ(popHead(q), "advertise");
  EXPECT_EQ(popHead(q), "telemetry");
  EXPECT_EQ(popHead(q), "key");
  EXPECT_TRUE(q.empty());
  EXPECT_EQ(q.counters().sent, 3u);
}

TEST(SendQueue, DropsTheOldestDataPastItsBudget) {
  SendQueue::Limits lim;
  lim.data_bytes = 100;
  SendQueue q(lim);
  for (int i = 0; i < 5; ++i) q.pushData(msg("t" + std::to_string(i), 38));  // 40 bytes each
  EXPECT_EQ(q.counters().dropped_data, 3u);
  EXPECT_EQ(popHead(q), "t3");
  EXPECT_EQ(popHead(q), "t4");
  q.pushData(msg("huge", 200));  // larger than the lane: never fits
  EXPECT_EQ(q.counters().dropped_data, 4u);
  EXPECT_TRUE(q.empty());
}

TEST(SendQueue, VideoWaitsForAKeyframeAndSkipsToTheNextAfterADrop) {
  SendQueue::Limits lim;
  lim.video_bytes = 100;
  SendQueue q(lim);
  q.pushVideo(7, false, msg("d0"));  // a new subscription starts at a keyframe
  EXPECT_EQ(q.counters().skipped_video, 1u);
  q.pushVideo(7, true, msg("k1", 28));
  q.pushVideo(7, false, msg("d1", 28));
  q.pushVideo(7, false, msg("d2", 28));
  q.pushVideo(7, false, msg("d3", 28));  // does not fit: dropped, the stream waits for a keyframe
  EXPECT_EQ(q.counters().dropped_video, 1u);
  q.pushVideo(7, false, msg("d4"));
  EXPECT_EQ(q.counters().skipped_video, 2u);
  // Another subscription is not affected.
  q.pushVideo(8, true, msg("other"));
  EXPECT_EQ(q.queuedMessages(), 4u);
  // The next keyframe replaces the stream's queued frames (all older) when it needs their room.
  q.pushVideo(7, true, msg("k2", 60));
  EXPECT_EQ(popHead(q), "other");
  EXPECT_EQ(popHead(q), "k2");
  EXPECT_TRUE(q.empty());
  q.pushVideo(7, false, msg("d5"));
  EXPECT_EQ(popHead(q), "d5");
}

TEST(SendQueue, RefusesControlPastItsLimit) {
  SendQueue::Limits lim;
  lim.control_bytes = 50;
  SendQueue q(lim);
  EXPECT_TRUE(q.pushControl(msg("a", 30)));
  EXPECT_FALSE(q.pushControl(msg("b", 30)));
  EXPECT_EQ(popHead(q), "a");
  EXPECT_TRUE(q.pushControl(msg("b", 30)));
}

TEST(SendQueue, AnEndedSubscriptionLeavesNothingQueued) {
  SendQueue q;
  OutMessage a = msg("a1"), b = msg("b1");
  a.subscription = 1;
  b.subscription = 2;
  q.pushData(a);
  q.pushData(b);
  q.pushVideo(1, true, msg("a-key"));
  q.forgetStream(1);  // unsubscribed: the client no longer knows id 1
  EXPECT_EQ(q.queuedMessages(), 1u);
  EXPECT_EQ(popHead(q), "b1");
  EXPECT_TRUE(q.empty());
  EXPECT_EQ(q.queuedBytes(), 0u);
}
