#pragma once
// A statement run on a catalog's database directly, not through the Catalog:
// what a test reads to check what the catalog wrote.
#include <string>
#include <vector>

namespace inspect::test {

/// The first column of every row of `sql` on a SQLite file, or on the
/// database of a "postgresql://" URL; one "error: ..." row when the
/// statement fails, none when the file cannot be opened.
std::vector<std::string> rawQuery(const std::string& path, const std::string& sql);

}  // namespace inspect::test
