#pragma once
// The command line of every program (robot_client, pc_server, mcu_sim, the
// experiments, the benchmarks and the test tools): one reader, one error type,
// one wording of its complaints. Each program keeps its own hand-written
// --help text; this reads the flags.
//
//   cli::ArgReader args(argc, argv);
//   while (args.next()) {
//     if (args.isHelp()) o.help = true;
//     else if (args.is("--rate")) o.rate = args.number(0.1, 100.0);
//     else if (args.is("--world")) o.world = args.path();
//     else if (args.is("--no-noise")) o.noise = false;
//     else args.unknown();
//   }
//
// Accepted: `--flag value` and `--flag=value`. A switch given a value
// (`--quick=1`) is refused. Complaints name the flag, as the config loader's
// do ("--rate: 'fast' is not a number", "--rate: 101 is out of range [0.1,
// 100]", "--bogus: unknown option (see --help)", "--world: missing value").
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace inspect::cli {

/// A bad command line; what() names the flag. Programs print it after their
/// name and exit with status 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ArgReader {
 public:
  /// The arguments without the program name.
  explicit ArgReader(std::vector<std::string> args);
  /// argv as main() receives it (argv[0] is skipped).
  ArgReader(int argc, char** argv);

  /// Moves to the next argument; false after the last. Throws when the
  /// previous switch was given an inline value it did not take.
  bool next();

  /// The current flag ("--rate" for "--rate=2"), or the positional argument.
  const std::string& flag() const { return flag_; }
  bool is(std::string_view name) const { return flag_ == name; }
  /// "--help" or "-h".
  bool isHelp() const { return flag_ == "--help" || flag_ == "-h"; }
  /// Not a flag (does not start with '-', or is "-" alone).
  bool isPositional() const;

  /// The flag's value as given (may be empty).
  std::string text();
  /// The flag's value, which must not be empty ("--truth: empty value").
  std::string path();
  /// A finite number in [min, max].
  double number(double min = -std::numeric_limits<double>::max(),
                double max = std::numeric_limits<double>::max());
  /// A finite number in (min, max] ("--duration: 0 is out of range (0, 1e+06]").
  double numberAbove(double min, double max = std::numeric_limits<double>::max());
  /// A whole number in [min, max] ("--seed: '-3' is not a whole number in [0, 4294967295]").
  int64_t integer(int64_t min, int64_t max);
  /// A whole number in [0, max], up to 2^64 - 1 (seeds).
  uint64_t unsignedInteger(uint64_t max = std::numeric_limits<uint64_t>::max());
  /// A port number 0-65535.
  uint16_t port();
  /// One of `choices` ("--plant: 'x' is not one of nominal, worn").
  std::string choice(std::initializer_list<std::string_view> choices);
  /// A comma list of non-empty items ("a,b,c"); an empty item is refused.
  std::vector<std::string> list();
  /// A picture size "WxH", each side in [64, 4096] ("--sizes: '64x9' is not WxH ...").
  std::pair<int, int> pictureSize();
  /// A comma list of picture sizes ("640x480,320x240").
  std::vector<std::pair<int, int>> pictureSizes();

  /// Throws "<flag>: unknown option (see --help)", or "unexpected argument 'x'"
  /// for a positional argument the program does not take.
  [[noreturn]] void unknown() const;
  /// Throws "<flag>: <why>".
  [[noreturn]] void fail(const std::string& why) const;

  /// Every argument (for checks such as "--attach takes no other flags").
  const std::vector<std::string>& all() const { return args_; }

 private:
  double finite(const std::string& v) const;

  std::vector<std::string> args_;
  std::size_t next_ = 0;
  std::string flag_;
  std::optional<std::string> inline_value_;
  bool value_taken_ = false;
};

/// For programs whose options live in main(): calls `on_flag` for each
/// argument (which reads it or calls unknown()); on a UsageError prints
/// "<program>: <what>" to stderr and exits with status 2.
void readOrExit(const char* program, int argc, char** argv, const std::function<void(ArgReader&)>& on_flag);

}  // namespace inspect::cli
