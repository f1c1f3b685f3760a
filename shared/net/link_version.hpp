#pragma once
// Link protocol version exchanged in the handshake (proto/inspect_robot/v1/link.proto).
#include <cstdint>

namespace inspect::net {
inline constexpr uint32_t kProtocolVersion = 2;
inline constexpr uint16_t kDefaultLinkPort = 7600;
inline constexpr uint16_t kDefaultVideoPort = 5600;
}  // namespace inspect::net
