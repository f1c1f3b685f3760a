#pragma once
// Session descriptions (RFC 4566, RFC 6184 section 8) for the camera stream,
// so that ffplay, VLC and GStreamer can play what the server forwards.
#include <cstdint>
#include <string>
#include <vector>

namespace inspect::video {

struct SdpParams {
  std::string session_name;            // e.g. "robot1 camera"
  std::string address = "127.0.0.1";   // where the player listens (c=)
  uint16_t port = 5700;                // RTP port of the player (m=)
  std::vector<uint8_t> sps, pps;       // without start codes; both or none
};

/// The SDP text: PT 96, H264/90000, packetization-mode=1, and
/// profile-level-id / sprop-parameter-sets when SPS/PPS are known.
std::string makeSdp(const SdpParams& p);

}  // namespace inspect::video
