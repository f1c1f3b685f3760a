// BackgroundFile: mcu_sim's log files written off the real-time loop.
#include "sim/mcu_sim/background_file.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include "tests/support/process.hpp"

namespace inspect::sim {
namespace {

std::string slurp(const std::string& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(BackgroundFile, LinesReachTheFileInOrderWithinAPeriodAndAllAtClose) {
  test::TempDir dir("bgfile");
  const std::string path = dir / "log.csv";
  std::string expect;
  {
    BackgroundFile f(path, "--truth", 10);
    for (int i = 0; i < 1000; ++i) {
      const std::string line = "T," + std::to_string(i) + "\n";
      f.append(line);
      expect += line;
    }
    f.sync();
    EXPECT_EQ(slurp(path), expect) << "sync() returns once everything appended is in the file";
    f.append("tail\n");
    expect += "tail\n";
    // A live reader sees the line within a few periods, without sync().
    bool seen = false;
    for (int i = 0; i < 200 && !seen; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      seen = slurp(path) == expect;
    }
    EXPECT_TRUE(seen) << "the writer thread wrote the tail within 1 s";
    f.append("last\n");
    expect += "last\n";
    EXPECT_EQ(f.droppedBytes(), 0u);
  }
  EXPECT_EQ(slurp(path), expect) << "the destructor writes out what is left";
}

TEST(BackgroundFile, AnUnwritablePathIsAnErrorNamingTheOptionAndThePath) {
  try {
    BackgroundFile f("/nonexistent-dir/truth.csv", "--truth");
    FAIL() << "opened an impossible path";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("--truth /nonexistent-dir/truth.csv: cannot open for writing"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace inspect::sim
