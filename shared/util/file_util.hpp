#pragma once
// Small file helpers shared by the programs.
#include <string>

namespace inspect {

/// Writes `text` to `path` atomically (a temporary file beside it, then
/// rename), so that readers never see half a file. Returns "" or the reason
/// it failed (naming the file).
std::string writeFileAtomically(const std::string& path, const std::string& text);

}  // namespace inspect
