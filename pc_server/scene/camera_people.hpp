#pragma once
// The people the robot's camera found in a picture (Telemetry.perception) as
// boxes over the camera image: foxglove.ImageAnnotations stamped with that
// picture's capture time, which is the camera channel's timestamp of the same
// picture, so Foxglove's Image panel draws them on the picture they were found
// in (docs/foxglove.md, "People on the camera image"). The live bridge and the
// recorder both use it. Pure: times come in as arguments.
#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <optional>

#include "foxglove/ImageAnnotations.pb.h"
#include "inspect_robot/v1/link.pb.h"
#include "shared/video/rtp_h264.hpp"

namespace inspect::server::scene {

/// One box per person (the detected picture's pixels scaled to the video's
/// size; 0 = the same size) and a label: "person +5 deg 6.2 m", or
/// "person +5 deg, feet not in view" when there is no range.
::foxglove::ImageAnnotations cameraPeople(const v1::Perception& p, uint32_t video_w, uint32_t video_h, uint64_t ns);

/// Gives a detected picture the timestamp its video frame was published with
/// on the camera channel (Foxglove pairs an image and its annotations by equal
/// times). It remembers the last kPictures frames (robot capture time ->
/// timestamp); a picture it has not seen (no video, a lost frame) is put on
/// the server's clock with the robot -> server offset of the access units
/// (the video receiver's), or before any video the link's (receive - send).
class CameraPeopleClock {
 public:
  static constexpr std::size_t kPictures = 64;  // 2 s at 30 fps: detections are later than that only when stale
  /// A frame published on the camera channel at `ns`; capture_server_us is the
  /// frame's capture time after the receiver's offset (0: none).
  void onAccessUnit(const video::Frame& f, uint64_t capture_server_us, uint64_t ns);
  /// The camera channel's timestamp of the picture of `p` (a head's
  /// Telemetry.perception) if it has not been returned before; nullopt
  /// otherwise. `to_wall_ns` turns a server monotonic µs into the channel's
  /// time (monoUsToWallNs).
  std::optional<uint64_t> fresh(const v1::Perception& p, int64_t link_offset_us, uint64_t (*to_wall_ns)(uint64_t));

 private:
  std::optional<int64_t> video_offset_us_;
  std::array<std::pair<uint64_t, uint64_t>, kPictures> pictures_{};  // robot capture µs -> ns (ring)
  std::size_t next_ = 0;
  uint64_t last_capture_us_ = 0;
};

}  // namespace inspect::server::scene
