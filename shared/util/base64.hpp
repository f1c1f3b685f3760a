#pragma once
// Standard base64 (RFC 4648 section 4, with '=' padding): SDP parameter sets
// (RFC 6184 sprop-parameter-sets) and the Foxglove WebSocket schemas.
#include <string>
#include <string_view>

namespace inspect::util {

/// The base64 text of `bytes`.
std::string base64(std::string_view bytes);

}  // namespace inspect::util
