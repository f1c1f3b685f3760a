#include "shared/util/cli_args.hpp"
#include "shared/util/number_text.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace inspect::cli {
namespace {

std::string bound(double v) {
  if (v >= std::numeric_limits<double>::max()) return "inf";
  if (v <= -std::numeric_limits<double>::max()) return "-inf";
  return util::significant(v, 6);
}

}  // namespace

ArgReader::ArgReader(std::vector<std::string> args) : args_(std::move(args)) {}

ArgReader::ArgReader(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) args_.emplace_back(argv[i]);
}

bool ArgReader::next() {
  if (inline_value_ && !value_taken_) fail("takes no value");
  inline_value_.reset();
  value_taken_ = false;
  if (next_ >= args_.size()) return false;
  flag_ = args_[next_++];
  if (const auto eq = flag_.find('='); flag_.rfind("--", 0) == 0 && eq != std::string::npos) {
    inline_value_ = flag_.substr(eq + 1);
    flag_.resize(eq);
  }
  return true;
}

bool ArgReader::isPositional() const { return flag_.empty() || flag_[0] != '-' || flag_ == "-"; }

std::string ArgReader::text() {
  value_taken_ = true;
  if (inline_value_) return *inline_value_;
  if (next_ >= args_.size()) fail("missing value");
  return args_[next_++];
}

std::string ArgReader::path() {
  std::string v = text();
  if (v.empty()) fail("empty value");
  return v;
}

double ArgReader::number(double min, double max) {
  const std::string v = text();
  const double d = finite(v);
  if (d < min || d > max) fail(v + " is out of range [" + bound(min) + ", " + bound(max) + "]");
  return d;
}

double ArgReader::numberAbove(double min, double max) {
  const std::string v = text();
  const double d = finite(v);
  if (!(d > min) || d > max) fail(v + " is out of range (" + bound(min) + ", " + bound(max) + (bound(max) == "inf" ? ")" : "]"));
  return d;
}

double ArgReader::finite(const std::string& v) const {
  double d = 0;
  const char* end = v.data() + v.size();
  const auto [p, ec] = std::from_chars(v.data(), end, d);
  if (v.empty() || ec != std::errc() || p != end || !std::isfinite(d)) fail("'" + v + "' is not a number");
  return d;
}

int64_t ArgReader::integer(int64_t min, int64_t max) {
  const std::string v = text();
  int64_t n = 0;
  const char* end = v.data() + v.size();
  const auto [p, ec] = std::from_chars(v.data(), end, n);
  if (v.empty() || ec != std::errc() || p != end || n < min || n > max)
    fail("'" + v + "' is not a whole number in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  return n;
}

uint64_t ArgReader::unsignedInteger(uint64_t max) {
  const std::string v = text();
  uint64_t n = 0;
  const char* end = v.data() + v.size();
  const auto [p, ec] = std::from_chars(v.data(), end, n);
  if (v.empty() || ec != std::errc() || p != end || n > max)
    fail("'" + v + "' is not a whole number in [0, " + std::to_string(max) + "]");
  return n;
}

uint16_t ArgReader::port() {
  const std::string v = text();
  int64_t n = 0;
  const char* end = v.data() + v.size();
  const auto [p, ec] = std::from_chars(v.data(), end, n);
  if (v.empty() || ec != std::errc() || p != end || n < 0 || n > 65535)
    fail("'" + v + "' is not a port number (0-65535)");
  return static_cast<uint16_t>(n);
}

std::string ArgReader::choice(std::initializer_list<std::string_view> choices) {
  std::string v = text();
  std::string names;
  for (const auto c : choices) {
    if (v == c) return v;
    names += (names.empty() ? "" : ", ") + std::string(c);
  }
  fail("'" + v + "' is not one of " + names);
}

std::vector<std::string> ArgReader::list() {
  const std::string v = path();
  std::vector<std::string> out;
  std::size_t begin = 0;
  while (begin <= v.size()) {
    const std::size_t comma = std::min(v.find(',', begin), v.size());
    if (comma == begin) fail("empty item in '" + v + "'");
    out.push_back(v.substr(begin, comma - begin));
    begin = comma + 1;
  }
  return out;
}

namespace {
bool parseSize(const std::string& t, std::pair<int, int>& out) {
  int w = 0, h = 0;
  char tail = 0;
  if (std::sscanf(t.c_str(), "%dx%d%c", &w, &h, &tail) != 2 || w < 64 || h < 64 || w > 4096 || h > 4096) return false;
  out = {w, h};
  return true;
}
}  // namespace

std::pair<int, int> ArgReader::pictureSize() {
  const std::string v = path();
  std::pair<int, int> out;
  if (!parseSize(v, out)) fail("'" + v + "' is not WxH with W and H in [64, 4096]");
  return out;
}

std::vector<std::pair<int, int>> ArgReader::pictureSizes() {
  std::vector<std::pair<int, int>> out;
  for (const auto& t : list()) {
    std::pair<int, int> wh;
    if (!parseSize(t, wh)) fail("'" + t + "' is not WxH with W and H in [64, 4096]");
    out.push_back(wh);
  }
  return out;
}

void ArgReader::unknown() const {
  if (isPositional()) throw UsageError("unexpected argument '" + flag_ + "'");
  throw UsageError(flag_ + ": unknown option (see --help)");
}

void ArgReader::fail(const std::string& why) const { throw UsageError(flag_ + ": " + why); }

void readOrExit(const char* program, int argc, char** argv, const std::function<void(ArgReader&)>& on_flag) {
  try {
    ArgReader a(argc, argv);
    while (a.next()) on_flag(a);
  } catch (const UsageError& e) {
    std::fprintf(stderr, "%s: %s\n", program, e.what());
    std::exit(2);
  }
}

}  // namespace inspect::cli
