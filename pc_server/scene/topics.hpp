#pragma once
// The one table of a robot's topics: the names the Foxglove bridge
// advertises live and the recorder writes into run.mcap are the same
// ("/robot1/telemetry"), so a layout made for the live view opens a recording
// unchanged (docs/recording.md, "Topics"). Runs recorded before had names
// without the robot ("/telemetry", "/event", ...): parseTopic() reads both.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace google::protobuf {
class Descriptor;
}

namespace inspect::server::scene {

enum class TopicKind {
  kTelemetry,
  kEvents,        // the robot's events
  kAcks,
  kAlarms,        // live only: gas alarms as they change (recordings have them as events)
  kCommands,      // recorded only: what the server sent
  kServerEvents,  // recorded only: run start and end, reconnects, gaps
  kRobotInfo,     // recorded only: the robot's Hello
  kCamera,
  kCameraPeople,
  kCameraWide,        // the wide head's stream (when the robot streams it)
  kCameraWidePeople,
  kTf,
  kScene,
  kLog,
  kVideoStats,    // live only: the stream's figures once a second
  kGasGrid,       // one per gas channel: "<robot>/gas/<channel>"
};

struct TopicDef {
  TopicKind kind;
  const char* leaf;         // after "/<robot>/" ("gas" for the grids: "gas/<channel>")
  const char* legacy;       // the name in runs recorded before (no robot prefix)
  bool live;                // advertised by the Foxglove bridge
  bool recorded;            // written into run.mcap
  bool video;               // the bridge's video lane
  const google::protobuf::Descriptor* (*type)();  // the message type
};

/// Every topic, in the order channels are made.
const std::vector<TopicDef>& topicTable();
const TopicDef& topicDef(TopicKind kind);

/// "/robot1/telemetry", "/robot1/gas/CH4" (gas: the channel, for kGasGrid).
std::string topicName(const std::string& robot, TopicKind kind, const std::string& gas = "");

/// What a topic name is: its kind, robot ("" for a legacy name) and gas channel.
struct TopicRef {
  TopicKind kind;
  std::string robot;
  std::string gas;
};
/// Reads the names topicName() makes and the legacy ones; nullopt for any other.
std::optional<TopicRef> parseTopic(std::string_view topic);

}  // namespace inspect::server::scene
