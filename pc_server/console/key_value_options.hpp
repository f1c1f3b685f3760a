#pragma once
// A console command's key=value options as a table (tune's; docs/console.md):
// each option's key, kind, range or words and what it sets. The words are
// parsed once, from the table, with the same error for every command: "'x'
// is not key=value", "evals=5: expected a number in [10, 100000]", "ref=spiral:
// expected circle, line or waypoints", "unknown option 'colour'".
#include <functional>
#include <string>
#include <vector>

namespace inspect::server {

struct KeyValueOption {
  std::string key;
  enum class Kind { kNumber, kWord } kind = Kind::kNumber;
  double lo = 0.0, hi = 0.0;       // kNumber: the accepted range
  std::vector<std::string> words;  // kWord: the accepted words (empty: any, checked by apply)
  /// Sets what the option sets from its value (the number for kNumber); "" or
  /// why the value was refused (printed as "<command>: <why>").
  std::function<std::string(double number, const std::string& text)> apply;
};

/// Applies "key=value" words in order; "" when every one was applied, else
/// the first error (`command` names the help to read: "(help tune)").
std::string applyKeyValues(const std::vector<std::string>& args, const std::vector<KeyValueOption>& table,
                           const std::string& command);

}  // namespace inspect::server
