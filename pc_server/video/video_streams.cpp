#include "pc_server/video/video_streams.hpp"

namespace inspect::server {

namespace {
constexpr const char* kWideSuffix = "/wide";
}  // namespace

std::string streamName(const std::string& robot, v1::CameraHead head) {
  return head == v1::WIDE_HEAD ? robot + kWideSuffix : robot;
}

StreamRef parseStreamName(const std::string& name) {
  const std::string suffix = kWideSuffix;
  if (name.size() > suffix.size() && name.ends_with(suffix))
    return {name.substr(0, name.size() - suffix.size()), v1::WIDE_HEAD};
  return {name, v1::PTZ_HEAD};
}

std::string streamFileStem(const std::string& name) {
  std::string stem = name;
  for (auto& c : stem)
    if (c == '/') c = '.';  // not in robot ids either: "robot1.wide" is nobody's own stem
  return stem;
}

std::string ffplayCommand(const std::string& sdp_path) {
  return "ffplay -protocol_whitelist file,udp,rtp -fflags nobuffer -flags low_delay " + sdp_path;
}

}  // namespace inspect::server
