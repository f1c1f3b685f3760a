#pragma once
// A robot's camera streams on the one video port (docs/video.md "The wide
// head's stream"): the PTZ head's is named after the robot ("robot1"), the
// wide head's "robot1/wide". Robot ids have no '/' (net::validRobotId), so
// the names never clash. The video receiver, the hub's SDP files and
// snapshots, the recorder and the Foxglove bridge all go by these names.
#include <string>

#include "inspect_robot/v1/link.pb.h"

namespace inspect::server {

/// "robot1" (PTZ_HEAD) or "robot1/wide" (WIDE_HEAD).
std::string streamName(const std::string& robot, v1::CameraHead head);

struct StreamRef {
  std::string robot;
  v1::CameraHead head = v1::PTZ_HEAD;
};
/// The inverse of streamName().
StreamRef parseStreamName(const std::string& name);

/// A file name's stem for the stream: "robot1", "robot1.wide".
std::string streamFileStem(const std::string& name);

/// The command line that plays a stream's SDP file with ffplay (docs/video.md).
std::string ffplayCommand(const std::string& sdp_path);

}  // namespace inspect::server
