#pragma once
// Handshake rules: which Hello the server accepts.
#include <optional>
#include <string>

#include "inspect_robot/v1/link.pb.h"

namespace inspect::server {

/// Why `hello` is refused, or nullopt when it is accepted.
std::optional<std::string> helloRejection(const v1::Hello& hello);

}  // namespace inspect::server
