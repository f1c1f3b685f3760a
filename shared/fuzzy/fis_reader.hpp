#pragma once
// Reads MATLAB .fis files ([System], [InputN], [OutputN], [Rules]) into a
// Fis, and refuses anything incomplete or ambiguous with an error that names
// the file, the line and the problem.
#include <string>
#include <string_view>

#include "shared/fuzzy/fis.hpp"

namespace inspect::fuzzy {

/// Reads and validates a .fis file. Throws FisError "path:line: reason".
Fis readFisFile(const std::string& path);
/// Parses and validates .fis text; `file_name` stands for the file in
/// messages. Throws FisError "file_name:line: reason".
Fis parseFis(std::string_view text, const std::string& file_name);

}  // namespace inspect::fuzzy
