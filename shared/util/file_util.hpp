#pragma once
// Small file helpers shared by the programs.
#include <string>

namespace inspect {

/// Writes `text` to `path` atomically (a temporary file beside it, then
/// rename), so that readers never see half a file. `durable`: the file and
/// then the rename are on the disk before it returns (fsync of the file and
/// of its folder), so a power cut leaves the old file or the new one.
/// Returns "" or the reason it failed (naming the file).
std::string writeFileAtomically(const std::string& path, const std::string& text, bool durable = false);

}  // namespace inspect
