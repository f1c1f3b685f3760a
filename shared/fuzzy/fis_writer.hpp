#pragma once
// Writes a Fis in MATLAB's .fis layout. Numbers are written in their shortest
// exact form, so reading the text back gives an equal Fis.
#include <string>

#include "shared/fuzzy/fis.hpp"

namespace inspect::fuzzy {

/// The .fis text of a system (comments first, as '%' lines).
std::string formatFis(const Fis& fis);
/// Writes formatFis() to a file; throws FisError if it cannot be written.
void writeFisFile(const Fis& fis, const std::string& path);

}  // namespace inspect::fuzzy
