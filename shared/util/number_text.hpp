#pragma once
// Numbers in messages, tables and reports: the one home of the project's
// number formatting (the console, the tuning host, the robot's events), and
// table cells.
#include <cstddef>
#include <string>

namespace inspect::util {

/// Fixed-point ("1.20"); never "-0.00".
std::string fmtFixed(double v, int decimals = 2);
/// Fixed-point with sign ("+0.30", "-1.20").
std::string fmtSigned(double v, int decimals = 2);
/// Fixed-point with `decimals`, trailing zeros removed ("1.93", "2", "-0.5").
std::string fmtShort(double v, int decimals = 3);
/// `v` with `digits` significant digits, as an ostream writes it ("0.2", "1.5e-05").
std::string significant(double v, int digits);
/// The shortest text that reads back as exactly `v` ("0.1", "1e-05", "nan"): for files written to be read again.
std::string shortest(double v);
/// A point in metres for messages: "(1.25, -0.50)".
std::string fmtPoint(double x_m, double y_m);
/// A table's cell: `s` padded with blanks to `width` on the right (text) or the left (numbers).
std::string padRight(std::string s, std::size_t width);
std::string padLeft(std::string s, std::size_t width);

}  // namespace inspect::util
