#pragma once
// The one rule for robot ids, used by the client's config and the server's handshake.
#include <algorithm>
#include <string>

namespace inspect::net {

/// True for ids of 1 to 64 characters from [A-Za-z0-9_-].
inline bool validRobotId(const std::string& id) {
  return !id.empty() && id.size() <= 64 && std::all_of(id.begin(), id.end(), [](char c) {
           return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
         });
}

}  // namespace inspect::net
