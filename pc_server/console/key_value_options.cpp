#include "pc_server/console/key_value_options.hpp"

#include <algorithm>

#include "shared/util/number_text.hpp"
#include "shared/util/text_parse.hpp"

namespace inspect::server {

std::string applyKeyValues(const std::vector<std::string>& args, const std::vector<KeyValueOption>& table,
                           const std::string& command) {
  for (const auto& a : args) {
    std::string k, v;
    if (!util::splitKeyValue(a, k, v)) return "'" + a + "' is not key=value (help " + command + ")";
    const KeyValueOption* opt = nullptr;
    for (const auto& o : table)
      if (o.key == k) opt = &o;
    if (!opt) return "unknown option '" + k + "' (help " + command + ")";
    double number = 0.0;
    if (opt->kind == KeyValueOption::Kind::kNumber) {
      const auto n = util::parseNumber(v);
      if (!n || !(*n >= opt->lo && *n <= opt->hi))
        return k + "=" + v + ": expected a number in [" + util::fmtShort(opt->lo) + ", " + util::fmtShort(opt->hi) + "]";
      number = *n;
    } else if (!opt->words.empty() && std::find(opt->words.begin(), opt->words.end(), v) == opt->words.end()) {
      return k + "=" + v + ": expected " + util::alternatives(opt->words);
    }
    if (std::string why = opt->apply(number, v); !why.empty()) return why;
  }
  return "";
}

}  // namespace inspect::server
