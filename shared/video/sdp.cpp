#include "shared/video/sdp.hpp"

#include <cstdio>

#include "shared/video/rtp_h264.hpp"

namespace inspect::video {

std::string base64(const std::vector<uint8_t>& b) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < b.size(); i += 3) {
    const uint32_t v = (b[i] << 16) | (b[i + 1] << 8) | b[i + 2];
    for (int k = 18; k >= 0; k -= 6) out += kAlphabet[(v >> k) & 63];
  }
  if (i + 1 == b.size()) {
    const uint32_t v = b[i] << 16;
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += "==";
  } else if (i + 2 == b.size()) {
    const uint32_t v = (b[i] << 16) | (b[i + 1] << 8);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += '=';
  }
  return out;
}

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
    s += std::string(";profile-level-id=") + pli + ";sprop-parameter-sets=" + base64(p.sps) + "," + base64(p.pps);
  }
  s += "\n";
  s += "a=recvonly\n";
  return s;
}

}  // namespace inspect::video
