#include "pc_server/scene/topics.hpp"

#include "foxglove/CompressedVideo.pb.h"
#include "foxglove/FrameTransforms.pb.h"
#include "foxglove/Grid.pb.h"
#include "foxglove/ImageAnnotations.pb.h"
#include "foxglove/Log.pb.h"
#include "foxglove/SceneUpdate.pb.h"
#include "inspect_robot/v1/link.pb.h"

namespace inspect::server::scene {

namespace {
template <typename M>
const google::protobuf::Descriptor* typeOf() {
  return M::descriptor();
}
}  // namespace

const std::vector<TopicDef>& topicTable() {
  using K = TopicKind;
  static const std::vector<TopicDef> table{
      {K::kTelemetry, "telemetry", "/telemetry", true, true, false, typeOf<v1::Telemetry>},
      {K::kEvents, "events", "/event", true, true, false, typeOf<v1::Event>},
      {K::kAcks, "acks", "/ack", true, true, false, typeOf<v1::Ack>},
      {K::kAlarms, "alarms", "", true, false, false, typeOf<v1::GasAlarm>},
      {K::kCommands, "commands", "/command", false, true, false, typeOf<v1::Command>},
      {K::kServerEvents, "server_events", "/server_event", false, true, false, typeOf<v1::Event>},
      {K::kRobotInfo, "robot_info", "/robot_info", false, true, false, typeOf<v1::Hello>},
      {K::kCamera, "camera", "/camera", true, true, true, typeOf<::foxglove::CompressedVideo>},
      {K::kCameraPeople, "camera_people", "/camera_people", true, true, false, typeOf<::foxglove::ImageAnnotations>},
      {K::kCameraWide, "camera_wide", "", true, true, true, typeOf<::foxglove::CompressedVideo>},
      {K::kCameraWidePeople, "camera_wide_people", "", true, true, false, typeOf<::foxglove::ImageAnnotations>},
      {K::kTf, "tf", "/tf", true, true, false, typeOf<::foxglove::FrameTransforms>},
      {K::kScene, "scene", "/scene", true, true, false, typeOf<::foxglove::SceneUpdate>},
      {K::kLog, "log", "/log", true, true, false, typeOf<::foxglove::Log>},
      {K::kVideoStats, "video_stats", "", true, false, false, typeOf<v1::VideoStats>},
      {K::kGasGrid, "gas", "/gas", true, true, false, typeOf<::foxglove::Grid>},
  };
  return table;
}

const TopicDef& topicDef(TopicKind kind) {
  for (const auto& d : topicTable())
    if (d.kind == kind) return d;
  return topicTable().front();  // unreachable: every kind is in the table
}

std::string topicName(const std::string& robot, TopicKind kind, const std::string& gas) {
  std::string name = "/" + robot + "/" + topicDef(kind).leaf;
  if (kind == TopicKind::kGasGrid) name += "/" + gas;
  return name;
}

std::optional<TopicRef> parseTopic(std::string_view topic) {
  if (topic.size() < 2 || topic[0] != '/') return std::nullopt;
  // A legacy name first: "/gas/CH4" is an old run's grid, not robot "gas".
  for (const auto& d : topicTable()) {
    if (!*d.legacy) continue;
    if (d.kind == TopicKind::kGasGrid) {
      if (topic.starts_with("/gas/") && topic.size() > 5 && topic.find('/', 5) == std::string_view::npos)
        return TopicRef{d.kind, "", std::string(topic.substr(5))};
    } else if (topic == d.legacy) {
      return TopicRef{d.kind, "", ""};
    }
  }
  const auto slash = topic.find('/', 1);
  if (slash == std::string_view::npos || slash == 1) return std::nullopt;
  const std::string robot(topic.substr(1, slash - 1));
  const std::string_view leaf = topic.substr(slash + 1);
  for (const auto& d : topicTable()) {
    if (d.kind == TopicKind::kGasGrid) {
      if (leaf.starts_with("gas/") && leaf.size() > 4 && leaf.find('/', 4) == std::string_view::npos)
        return TopicRef{d.kind, robot, std::string(leaf.substr(4))};
    } else if (leaf == d.leaf) {
      return TopicRef{d.kind, robot, ""};
    }
  }
  return std::nullopt;
}

}  // namespace inspect::server::scene
