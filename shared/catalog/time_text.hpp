#pragma once
// Times in the run catalog: Unix seconds in the tables, ISO 8601 UTC in
// text (formatIsoUtc / parseIsoUtc in catalog.hpp). Internal to shared/catalog.
#include <ctime>
#include <string>

#include "shared/catalog/catalog.hpp"

namespace inspect::catalog {

double unixSeconds(Time t);
Time fromUnix(double s);
/// The calendar parts of `t` in UTC.
std::tm utcParts(Time t);
/// `t` in UTC through strftime's `fmt`.
std::string strftimeUtc(Time t, const char* fmt);

}  // namespace inspect::catalog
