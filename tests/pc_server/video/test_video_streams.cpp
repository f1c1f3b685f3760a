// A robot's camera streams by name (pc_server/video/video_streams): the PTZ
// head's is the robot's id, the wide head's "<robot>/wide"; file stems never
// clash with another robot's own.
#include <gtest/gtest.h>

#include "pc_server/video/video_streams.hpp"
#include "shared/net/robot_id.hpp"

using namespace inspect;
using namespace inspect::server;

TEST(VideoStreams, NamesReadBackAndStemsNeverClash) {
  EXPECT_EQ(streamName("robot1", v1::PTZ_HEAD), "robot1");
  EXPECT_EQ(streamName("robot1", v1::WIDE_HEAD), "robot1/wide");
  for (const std::string robot : {"robot1", "r", "wide", "a_wide", "x-y"})
    for (const auto head : {v1::PTZ_HEAD, v1::WIDE_HEAD}) {
      const StreamRef ref = parseStreamName(streamName(robot, head));
      EXPECT_EQ(ref.robot, robot);
      EXPECT_EQ(ref.head, head) << robot;
    }
  EXPECT_EQ(streamFileStem("robot1"), "robot1");
  EXPECT_EQ(streamFileStem("robot1/wide"), "robot1.wide");
  // A robot named robot1_wide or robot1-wide keeps its own files.
  EXPECT_NE(streamFileStem(streamName("robot1", v1::WIDE_HEAD)), streamFileStem("robot1_wide"));
  EXPECT_NE(streamFileStem(streamName("robot1", v1::WIDE_HEAD)), streamFileStem("robot1-wide"));
  EXPECT_FALSE(net::validRobotId("robot1/wide")) << "no robot has a wide stream's name";
  EXPECT_FALSE(net::validRobotId("robot1.wide")) << "nor its file stem";
  EXPECT_EQ(parseStreamName("/wide").robot, "/wide") << "not a wide stream: no robot before the suffix";
}
