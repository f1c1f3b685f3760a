#include "shared/video/sdp.hpp"

#include <cstdio>

#include "shared/util/base64.hpp"
#include "shared/video/rtp_h264.hpp"

namespace inspect::video {

namespace {
std::string b64(const std::vector<uint8_t>& b) {
  return util::base64(std::string_view(reinterpret_cast<const char*>(b.data()), b.size()));
}
}  // namespace

std::string makeSdp(const SdpParams& p) {
  std::string s;
  s += "v=0\n";
  s += "o=- 0 0 IN IP4 " + p.address + "\n";
  s += "s=" + (p.session_name.empty() ? std::string("camera") : p.session_name) + "\n";
  s += "c=IN IP4 " + p.address + "\n";
  s += "t=0 0\n";
  s += "m=video " + std::to_string(p.port) + " RTP/AVP " + std::to_string(kPayloadType) + "\n";
  s += "a=rtpmap:" + std::to_string(kPayloadType) + " H264/" + std::to_string(kClockRate) + "\n";
  s += "a=fmtp:" + std::to_string(kPayloadType) + " packetization-mode=1";
  if (p.sps.size() >= 4 && !p.pps.empty()) {
    char pli[8];
    std::snprintf(pli, sizeof pli, "%02x%02x%02x", p.sps[1], p.sps[2], p.sps[3]);
    s += std::string(";profile-level-id=") + pli + ";sprop-parameter-sets=" + b64(p.sps) + "," + b64(p.pps);
  }
  s += "\n";
  s += "a=recvonly\n";
  return s;
}

}  // namespace inspect::video
