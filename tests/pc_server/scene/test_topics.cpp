// The one topic table: live and recorded names are the same, and the names of
// runs recorded before (no robot prefix) still read as what they were.
#include <gtest/gtest.h>

#include <set>

#include "pc_server/scene/topics.hpp"

using namespace inspect::server::scene;

TEST(Topics, NamesCarryTheRobotAndReadBack) {
  EXPECT_EQ(topicName("robot1", TopicKind::kTelemetry), "/robot1/telemetry");
  EXPECT_EQ(topicName("robot1", TopicKind::kEvents), "/robot1/events");
  EXPECT_EQ(topicName("r2", TopicKind::kGasGrid, "CH4"), "/r2/gas/CH4");
  std::set<std::string> names;
  for (const auto& d : topicTable()) {
    const std::string name = topicName("robot7", d.kind, "H2S");
    EXPECT_TRUE(names.insert(name).second) << name << " twice";
    const auto back = parseTopic(name);
    ASSERT_TRUE(back) << name;
    EXPECT_EQ(back->kind, d.kind) << name;
    EXPECT_EQ(back->robot, "robot7") << name;
    EXPECT_EQ(back->gas, d.kind == TopicKind::kGasGrid ? "H2S" : "") << name;
    EXPECT_TRUE(d.live || d.recorded) << d.leaf;
    EXPECT_NE(d.type(), nullptr) << d.leaf;
  }
}

TEST(Topics, RunsRecordedBeforeStillRead) {
  const std::pair<const char*, TopicKind> old[] = {
      {"/telemetry", TopicKind::kTelemetry}, {"/event", TopicKind::kEvents},          {"/ack", TopicKind::kAcks},
      {"/command", TopicKind::kCommands},    {"/server_event", TopicKind::kServerEvents}, {"/robot_info", TopicKind::kRobotInfo},
      {"/camera", TopicKind::kCamera},       {"/tf", TopicKind::kTf},                  {"/scene", TopicKind::kScene}};
  for (const auto& [name, kind] : old) {
    const auto t = parseTopic(name);
    ASSERT_TRUE(t) << name;
    EXPECT_EQ(t->kind, kind) << name;
    EXPECT_EQ(t->robot, "") << name;
  }
  const auto grid = parseTopic("/gas/CO");
  ASSERT_TRUE(grid);
  EXPECT_EQ(grid->kind, TopicKind::kGasGrid);
  EXPECT_EQ(grid->gas, "CO");
  EXPECT_EQ(grid->robot, "");
  for (const char* bad : {"", "/", "telemetry", "/robot1/unknown", "//telemetry", "/robot1/gas/", "/robot1/gas/a/b"})
    EXPECT_FALSE(parseTopic(bad)) << bad;
}
