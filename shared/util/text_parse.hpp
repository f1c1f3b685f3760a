#pragma once
// Strict parsing of typed words: numbers, integers, blanks-separated words,
// key=value (the console, the operator socket, route files). Number
// formatting is shared/util/number_text.hpp.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace inspect::util {

/// Whole-string finite decimal number ("1.5", "-2", "1e-3"); nullopt otherwise.
std::optional<double> parseNumber(std::string_view text);
/// Whole-string integer (decimal, or hex with 0x); nullopt otherwise.
std::optional<long long> parseInteger(std::string_view text);
/// Splits on blanks (spaces and tabs).
std::vector<std::string> splitWords(std::string_view text);
/// Removes leading and trailing blanks (and a trailing '\r').
std::string trim(std::string_view text);
/// The words as a list for a message: "a, b or c" ("a" alone, "a or b").
std::string alternatives(const std::vector<std::string>& words);
/// "key=value" into its two halves (neither empty); false otherwise.
bool splitKeyValue(const std::string& a, std::string& k, std::string& v);

}  // namespace inspect::util
