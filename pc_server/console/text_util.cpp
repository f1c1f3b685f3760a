#include "pc_server/console/text_util.hpp"

namespace inspect::server {

std::string gainsText(const control::GainSet& g) {
  std::string out;
  for (const char* n : control::kGainNames) out += (out.empty() ? "" : " ") + std::string(n) + "=" + fmtShort(control::gainValue(g, n), 4);
  return out;
}

}  // namespace inspect::server
