#pragma once
// Small text helpers of the console: strict number parsing, word splitting, number formatting.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace inspect::server {

/// Whole-string finite decimal number ("1.5", "-2", "1e-3"); nullopt otherwise.
std::optional<double> parseNumber(std::string_view text);
/// Whole-string integer (decimal, or hex with 0x); nullopt otherwise.
std::optional<long long> parseInteger(std::string_view text);
/// Splits on blanks (spaces and tabs).
std::vector<std::string> splitWords(std::string_view text);
/// Removes leading and trailing blanks (and a trailing '\r').
std::string trim(std::string_view text);
/// Fixed-point with `decimals`, trailing zeros removed ("1.93", "2", "-0.5").
std::string fmtShort(double v, int decimals = 3);
/// Fixed-point with sign ("+0.30", "-1.20").
std::string fmtSigned(double v, int decimals = 2);
/// Fixed-point ("1.20").
std::string fmtFixed(double v, int decimals = 2);

}  // namespace inspect::server
