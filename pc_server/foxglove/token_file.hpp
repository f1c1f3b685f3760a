#pragma once
// The Foxglove bridge's token (docs/foxglove.md, "Security"): a shared secret
// in a file only its owner may read. Clients present it in the URL
// (ws://host:8765/?token=...) or as "Authorization: Bearer ...".
#include <string>

namespace inspect::server::foxglove {

/// Reads the token in `path` (its first line, 16 to 256 printable characters),
/// or, when there is no such file, creates it (mode 0600) with a new random
/// token (32 hex digits from OpenSSL's RAND_bytes). Throws util::StartupError naming
/// the file and what was wrong.
std::string loadOrCreateToken(const std::string& path);

}  // namespace inspect::server::foxglove
