// The fis_eval command-line tool: rows in, rows out, bad rows named by line,
// load errors as one line with exit status 2.
#include <sys/wait.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "shared/fuzzy/engine.hpp"
#include "shared/fuzzy/fis_reader.hpp"
#include "tests/support/paths.hpp"

namespace inspect::fuzzy {
namespace {

namespace fs = std::filesystem;
const std::string kBin = inspect::test::binPath("fis_eval");
const std::string kPid = inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis");

struct Result {
  int status = -1;
  std::string out;
  std::string err;
};

Result runTool(const std::string& args, const std::string& stdin_text) {
  const fs::path dir = fs::temp_directory_path() / ("inspect_fis_eval_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "in.txt") << stdin_text;
  const std::string cmd = kBin + " " + args + " <'" + (dir / "in.txt").string() + "' >'" + (dir / "out.txt").string() +
                          "' 2>'" + (dir / "err.txt").string() + "'";
  Result r;
  const int raw = std::system(cmd.c_str());
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  std::stringstream o, e;
  o << std::ifstream(dir / "out.txt").rdbuf();
  e << std::ifstream(dir / "err.txt").rdbuf();
  r.out = o.str();
  r.err = e.str();
  fs::remove_all(dir);
  return r;
}

TEST(FisEval, PrintsOneRowPerInputRowMatchingTheEngine) {
  const Result r = runTool("'" + kPid + "'", "e ec\n# a comment\n\n0.5 -1.25\n  -3 3\n");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err, "");
  Engine e(readFisFile(kPid));
  std::istringstream lines(r.out);
  for (const auto& in : {std::array<double, 2>{0.5, -1.25}, std::array<double, 2>{-3, 3}}) {
    std::array<double, 3> expect{}, got{};
    e.evaluate(in, expect);
    ASSERT_TRUE(lines >> got[0] >> got[1] >> got[2]) << r.out;
    for (std::size_t o = 0; o < 3; ++o) EXPECT_NEAR(got[o], expect[o], 1e-9 * std::max(1.0, std::abs(expect[o])));
  }
  std::string extra;
  EXPECT_FALSE(lines >> extra) << "more output than rows: " << r.out;
}

TEST(FisEval, BadRowsAreNamedByLineAndSkipped) {
  const Result r = runTool("'" + kPid + "'", "0 0\n1 2 3\n0 abc\n1 1\n");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("line 2: expected 2 input values, got 3"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("line 3: 'abc' is not a number"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 2) << r.out;
}

TEST(FisEval, NonFiniteInputPrintsNaN) {
  const Result r = runTool("'" + kPid + "'", "nan 0\n");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.out, "nan nan nan\n");
}

TEST(FisEval, LoadErrorIsOneLineAndExit2) {
  const fs::path bad = fs::temp_directory_path() / ("inspect_fis_eval_bad_" + std::to_string(::getpid()) + ".fis");
  std::string text;
  {
    std::stringstream ss;
    ss << std::ifstream(kPid).rdbuf();
    text = ss.str();
  }
  const std::string from = "MF3='NS':'trimf',[-2 -1 0]";
  text.replace(text.find(from), from.size(), "MF3='NS':'trimf',[-2 -1]");
  std::ofstream(bad) << text;
  const Result r = runTool("'" + bad.string() + "'", "");
  fs::remove(bad);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find(".fis:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(": MF3: trimf needs 3 parameters, got 2"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(runTool("/nonexistent.fis", "").status, 2);
  EXPECT_EQ(runTool("", "").status, 2);
}

TEST(FisEval, HelpExitsZero) {
  const Result r = runTool("--help", "");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.out.find("usage: fis_eval"), std::string::npos);
}

}  // namespace
}  // namespace inspect::fuzzy
