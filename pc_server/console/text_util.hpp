#pragma once
// Small text helpers of the console: strict number parsing, word splitting
// (number formatting: shared/util/number_text.hpp).
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "shared/control/gain_set.hpp"
#include "shared/util/number_text.hpp"

namespace inspect::server {

/// Whole-string finite decimal number ("1.5", "-2", "1e-3"); nullopt otherwise.
std::optional<double> parseNumber(std::string_view text);
/// Whole-string integer (decimal, or hex with 0x); nullopt otherwise.
std::optional<long long> parseInteger(std::string_view text);
/// Splits on blanks (spaces and tabs).
std::vector<std::string> splitWords(std::string_view text);
/// Removes leading and trailing blanks (and a trailing '\r').
std::string trim(std::string_view text);
/// "key=value" into its two halves (neither empty); false otherwise.
bool splitKeyValue(const std::string& a, std::string& k, std::string& v);
/// Every tracking gain as "kp=11.94 ki=11.5 ...".
std::string gainsText(const control::GainSet& g);

/// How the console shows a telemetry value the robot left out (link
/// protocol 2, docs/link-protocol.md "Presence"): never as 0.
inline constexpr const char* kUnknown = "unknown";

using util::fmtFixed;
using util::fmtShort;
using util::fmtSigned;

}  // namespace inspect::server
