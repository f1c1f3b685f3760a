#pragma once
// The console's text: gains as text, how an unknown value reads; the typed-word
// parsing (shared/util/text_parse.hpp) and number formatting it uses.
#include <string>

#include "shared/control/gain_set.hpp"
#include "shared/util/number_text.hpp"
#include "shared/util/text_parse.hpp"

namespace inspect::server {

/// Every tracking gain as "kp=11.94 ki=11.5 ...".
std::string gainsText(const control::GainSet& g);

/// How the console shows a telemetry value the robot left out (link
/// protocol 2, docs/link-protocol.md "Presence"): never as 0.
inline constexpr const char* kUnknown = "unknown";

using util::fmtFixed;
using util::fmtShort;
using util::fmtSigned;
using util::padLeft;
using util::padRight;
using util::parseInteger;
using util::parseNumber;
using util::splitKeyValue;
using util::splitWords;
using util::trim;

}  // namespace inspect::server
