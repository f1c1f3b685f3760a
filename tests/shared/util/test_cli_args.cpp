// The command-line reader every program uses (shared/util/cli_args.hpp).
#include "shared/util/cli_args.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace inspect::cli {
namespace {

struct Parsed {
  std::string world;
  double rate = 1;
  double duration = 0;
  int64_t seed = 1;
  uint16_t port = 0;
  std::string plant = "nominal";
  std::vector<std::string> only;
  bool quick = false;
  bool help = false;
  std::vector<std::string> files;
};

Parsed parse(const std::vector<std::string>& args) {
  Parsed p;
  ArgReader a(args);
  while (a.next()) {
    if (a.isHelp()) p.help = true;
    else if (a.is("--world")) p.world = a.path();
    else if (a.is("--rate")) p.rate = a.number(0.1, 100);
    else if (a.is("--duration")) p.duration = a.numberAbove(0, 1e6);
    else if (a.is("--seed")) p.seed = a.integer(0, 4294967295LL);
    else if (a.is("--port")) p.port = a.port();
    else if (a.is("--plant")) p.plant = a.choice({"nominal", "worn"});
    else if (a.is("--only")) p.only = a.list();
    else if (a.is("--quick")) p.quick = true;
    else if (a.isPositional()) p.files.push_back(a.flag());
    else a.unknown();
  }
  return p;
}

std::string errorOf(const std::vector<std::string>& args) {
  try {
    (void)parse(args);
  } catch (const UsageError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(CliArgs, ReadsSeparateAndInlineValues) {
  const Parsed p = parse({"--world", "w.yaml", "--rate=2.5", "--duration", "3", "--seed=77", "--port", "0",
                          "--plant", "worn", "--only=a,b", "--quick", "in.fis", "-h"});
  EXPECT_EQ(p.world, "w.yaml");
  EXPECT_DOUBLE_EQ(p.rate, 2.5);
  EXPECT_DOUBLE_EQ(p.duration, 3.0);
  EXPECT_EQ(p.seed, 77);
  EXPECT_EQ(p.port, 0);
  EXPECT_EQ(p.plant, "worn");
  EXPECT_EQ(p.only, (std::vector<std::string>{"a", "b"}));
  EXPECT_TRUE(p.quick);
  EXPECT_TRUE(p.help);
  EXPECT_EQ(p.files, std::vector<std::string>{"in.fis"});
}

TEST(CliArgs, ValueMayStartWithADash) {
  // "--rate -1" is a value out of range, not a missing value.
  EXPECT_EQ(errorOf({"--rate", "-1"}), "--rate: -1 is out of range [0.1, 100]");
  EXPECT_EQ(parse({"--world", "-"}).world, "-");
}

TEST(CliArgs, ComplaintsNameTheFlag) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--world"}, "--world: missing value"},
      {{"--world="}, "--world: empty value"},
      {{"--rate", "fast"}, "--rate: 'fast' is not a number"},
      {{"--rate", "nan"}, "--rate: 'nan' is not a number"},
      {{"--rate", "2x"}, "--rate: '2x' is not a number"},
      {{"--rate", "101"}, "--rate: 101 is out of range [0.1, 100]"},
      {{"--duration", "0"}, "--duration: 0 is out of range (0, 1e+06]"},
      {{"--seed", "-3"}, "--seed: '-3' is not a whole number in [0, 4294967295]"},
      {{"--seed", "1.5"}, "--seed: '1.5' is not a whole number in [0, 4294967295]"},
      {{"--port", "70000"}, "--port: '70000' is not a port number (0-65535)"},
      {{"--plant", "new"}, "--plant: 'new' is not one of nominal, worn"},
      {{"--only", "a,,b"}, "--only: empty item in 'a,,b'"},
      {{"--quick=1"}, "--quick: takes no value"},
      {{"--frobnicate"}, "--frobnicate: unknown option (see --help)"},
      {{"-x"}, "-x: unknown option (see --help)"},
  };
  for (const auto& [args, want] : cases) EXPECT_EQ(errorOf(args), want);
}

TEST(CliArgs, PositionalNotTakenIsUnexpected) {
  ArgReader a({"stray"});
  ASSERT_TRUE(a.next());
  EXPECT_TRUE(a.isPositional());
  try {
    a.unknown();
    FAIL() << "no throw";
  } catch (const UsageError& e) {
    EXPECT_STREQ(e.what(), "unexpected argument 'stray'");
  }
}

TEST(CliArgs, ArgvSkipsTheProgramName) {
  char prog[] = "prog", flag[] = "--quick";
  char* argv[] = {prog, flag, nullptr};
  ArgReader a(2, argv);
  ASSERT_TRUE(a.next());
  EXPECT_TRUE(a.is("--quick"));
  EXPECT_FALSE(a.next());
  EXPECT_EQ(a.all().size(), 1u);
}

}  // namespace
}  // namespace inspect::cli
