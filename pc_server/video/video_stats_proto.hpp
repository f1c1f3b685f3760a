#pragma once
// The server's receive figures of one stream as the protobuf message the
// Foxglove bridge publishes on /<robot>/video_stats (with the robot's own
// VideoStatus beside them).
#include "inspect_robot/v1/link.pb.h"
#include "shared/video/video_receiver.hpp"

namespace inspect::server {

v1::VideoReceiveStats toProto(const video::StreamStats& s);

}  // namespace inspect::server
