// Gains files (shared/config/gains_file.hpp): exact round trips, defaults for
// missing keys, refused keys and values with messages naming file and key,
// the .fis beside the YAML and its fuzzy-PID shape, the catalog's JSON.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shared/config/gains_file.hpp"
#include "shared/fuzzy/fis_reader.hpp"
#include "tests/support/paths.hpp"
#include "tests/support/process.hpp"

using namespace inspect;
using config::ConfigError;
namespace fs = std::filesystem;

namespace {


// The ConfigError message of `f`, "" if it does not throw one.
template <class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

// Gains whose decimal forms are long: only an exact writer brings them back.
control::GainSet awkwardGains() {
  control::GainSet g;
  g.fuzzy.base.kp = 0.1 + 0.2;  // 0.30000000000000004
  g.fuzzy.base.ki = 1.0 / 3.0;
  g.fuzzy.base.kd = 100.0;      // upper bound
  g.fuzzy.ke = 1e-7;
  g.fuzzy.kec = 0.0;            // lower bound
  g.fuzzy.k1 = 9.000000000000002;
  g.fuzzy.k2 = 2.0 / 7.0;
  g.fuzzy.k3 = 12345.678 / 1000.0;
  g.aux.a1 = -20.0;             // lower bound
  g.aux.a2 = -1.0 / 3.0;
  g.aux.a3 = -0.0;
  return g;
}

class GainsFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("gains_file_test_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& text) const {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }

  fs::path dir_;
  const control::GainSet defaults_{};  // the paper's
};

TEST_F(GainsFileTest, YamlRoundTripKeepsEveryDoubleExactly) {
  const control::GainSet g = awkwardGains();
  const std::string text = config::gainsYaml(g, "tuned for robot1\nsecond line", "");
  EXPECT_EQ(text.rfind("# tuned for robot1\n# second line\n", 0), 0u) << text;
  EXPECT_EQ(text.find("fis:"), std::string::npos) << text;
  const auto loaded = config::loadGainsFile(write("g.yaml", text), defaults_);
  for (const char* name : control::kGainNames) {
    SCOPED_TRACE(name);
    EXPECT_EQ(control::gainValue(loaded.gains, name), control::gainValue(g, name));
  }
  EXPECT_TRUE(control::sameGains(loaded.gains, g));
  EXPECT_TRUE(std::signbit(loaded.gains.aux.a3));  // even -0 survives
  EXPECT_EQ(loaded.fis_path, "");
}

TEST_F(GainsFileTest, KeysAreWrittenInTheFixedOrderWithTheirBounds) {
  const std::string text = config::gainsYaml(defaults_, "", "tuned.fis");
  std::vector<std::string> keys;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);)
    if (!line.empty() && line[0] != '#') keys.push_back(line.substr(0, line.find(':')));
  std::vector<std::string> want(control::kGainNames.begin(), control::kGainNames.end());
  want.push_back("fis");
  EXPECT_EQ(keys, want) << text;
  EXPECT_NE(text.find("kp: 9 "), std::string::npos) << text;
  EXPECT_NE(text.find("a2: -1.2 "), std::string::npos) << text;
  EXPECT_NE(text.find("[-20, 0]"), std::string::npos) << text;
  EXPECT_NE(text.find("fis: \"tuned.fis\""), std::string::npos) << text;
}

TEST_F(GainsFileTest, MissingKeysKeepTheDefaults) {
  const auto loaded = config::loadGainsFile(write("g.yaml", "# only two\nkp: 12.5\na3: -0.75\n"), defaults_);
  control::GainSet want = defaults_;
  want.fuzzy.base.kp = 12.5;
  want.aux.a3 = -0.75;
  EXPECT_TRUE(control::sameGains(loaded.gains, want));
  const auto empty = config::loadGainsFile(write("empty.yaml", "# nothing\n"), defaults_);
  EXPECT_TRUE(control::sameGains(empty.gains, defaults_));
}

TEST_F(GainsFileTest, UnknownKeyIsAnErrorNamingFileAndKey) {
  const std::string path = write("g.yaml", "kp: 9\nkq: 2\n");
  const std::string err = errorOf([&] { config::loadGainsFile(path, defaults_); });
  EXPECT_EQ(err, path + ": kq: unknown key (misspelt, or not used by this program)");
}

TEST_F(GainsFileTest, BadValuesAreErrorsNamingFileAndKey) {
  struct Case {
    const char* yaml;
    const char* expected;  // after "path: "
  };
  const Case cases[] = {
      {"kp: 100.5\n", "kp: 100.5 is out of range [0, 100]"},
      {"ke: -0.1\n", "ke: -0.1 is out of range [0, 100]"},
      {"a2: 3\n", "a2: 3 is out of range [-20, 0]"},
      {"a1: -21\n", "a1: -21 is out of range [-20, 0]"},
      {"kd: .nan\n", "kd: must be finite"},
      {"k1: fast\n", "k1: 'fast' is not a number"},
      {"fis: [a, b]\n", "fis: must be a string"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.yaml);
    const std::string path = write("bad.yaml", c.yaml);
    EXPECT_EQ(errorOf([&] { config::loadGainsFile(path, defaults_); }), path + ": " + c.expected);
  }
}

TEST_F(GainsFileTest, InvalidDefaultsAreReportedToo) {
  control::GainSet bad = defaults_;
  bad.aux.a1 = 1.0;
  const std::string path = write("g.yaml", "kp: 9\n");
  const std::string err = errorOf([&] { config::loadGainsFile(path, bad); });
  EXPECT_EQ(err, path + ": a1 = 1 is outside [-20, 0] (a default the file does not set)");
}

TEST_F(GainsFileTest, MissingFileIsAnErrorNamingIt) {
  const std::string path = (dir_ / "nope.yaml").string();
  EXPECT_EQ(errorOf([&] { config::loadGainsFile(path, defaults_); }), path + ": cannot open file");
  EXPECT_EQ(errorOf([&] { config::importGains(path, defaults_, nullptr); }), path + ": cannot open file");
}

TEST_F(GainsFileTest, ExportWritesTheFisBesideAndImportReadsBoth) {
  const fuzzy::Fis fis = fuzzy::readFisFile(inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis"));
  const control::GainSet g = awkwardGains();
  const std::string yaml = (dir_ / "gains_tuned.yaml").string();
  config::exportGains(g, fis, yaml, "from a test");
  ASSERT_TRUE(fs::exists(dir_ / "gains_tuned.fis"));
  const std::string text = inspect::test::readFile(yaml);
  EXPECT_EQ(text.rfind("# from a test\n", 0), 0u) << text;
  EXPECT_NE(text.find("fis: \"gains_tuned.fis\""), std::string::npos) << text;

  fuzzy::Fis back;
  const auto loaded = config::importGains(yaml, defaults_, &back);
  EXPECT_TRUE(control::sameGains(loaded.gains, g));
  EXPECT_EQ(loaded.fis_path, (dir_ / "gains_tuned.fis").string());
  EXPECT_EQ(back, fis);
  // No file left behind but the two.
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir_)) ++n;
  EXPECT_EQ(n, 2u);
}

TEST_F(GainsFileTest, AbsoluteFisPathIsKept) {
  const std::string fis = inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis");
  const std::string yaml = write("g.yaml", config::gainsYaml(defaults_, "", fis));
  fuzzy::Fis back;
  const auto loaded = config::importGains(yaml, defaults_, &back);
  EXPECT_EQ(loaded.fis_path, fis);
  EXPECT_EQ(back.inputs.size(), 2u);
}

TEST_F(GainsFileTest, ImportRefusesAFisWithTheWrongShape) {
  // The speed strategy's system: 3 inputs, 1 output.
  fs::copy_file(inspect::test::srcPath("config/fuzzy/speed_strategy.fis"), dir_ / "speed.fis");
  const std::string yaml = write("g.yaml", config::gainsYaml(defaults_, "", "speed.fis"));
  fuzzy::Fis untouched;
  untouched.name = "sentinel";
  const std::string err = errorOf([&] { config::importGains(yaml, defaults_, &untouched); });
  EXPECT_EQ(err.rfind(yaml + ": fis: fuzzy-PID system '", 0), 0u) << err;
  EXPECT_NE(err.find("must have 2 inputs (e, ec) and 3 outputs (kpx, kix, kdx)"), std::string::npos) << err;
  EXPECT_EQ(untouched.name, "sentinel");
  // Reading the gains alone does not look at the .fis.
  EXPECT_EQ(config::loadGainsFile(yaml, defaults_).fis_path, (dir_ / "speed.fis").string());
}

TEST_F(GainsFileTest, ImportNamesAMissingOrBrokenFis) {
  const std::string missing = write("m.yaml", config::gainsYaml(defaults_, "", "gone.fis"));
  EXPECT_EQ(errorOf([&] { config::importGains(missing, defaults_, nullptr); }),
            missing + ": fis: " + (dir_ / "gone.fis").string() + ": cannot open file");
  write("broken.fis", "[System]\nName='x'\n");
  const std::string broken = write("b.yaml", config::gainsYaml(defaults_, "", "broken.fis"));
  const std::string err = errorOf([&] { config::importGains(broken, defaults_, nullptr); });
  EXPECT_EQ(err.rfind(broken + ": fis: " + (dir_ / "broken.fis").string() + ":", 0), 0u) << err;
}

TEST_F(GainsFileTest, ExportRefusesInvalidGainsAndWritesNothing) {
  const fuzzy::Fis fis = fuzzy::readFisFile(inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis"));
  control::GainSet g = defaults_;
  g.fuzzy.base.kp = -1.0;
  const std::string yaml = (dir_ / "g.yaml").string();
  EXPECT_EQ(errorOf([&] { config::exportGains(g, fis, yaml, ""); }),
            yaml + ": refusing to write invalid gains: kp = -1 is outside [0, 100]");
  EXPECT_TRUE(fs::is_empty(dir_));
  const std::string clash = (dir_ / "g.fis").string();
  EXPECT_EQ(errorOf([&] { config::exportGains(defaults_, fis, clash, ""); }),
            clash + ": a gains file must not end in .fis (its fuzzy system is written beside it as <stem>.fis)");
  EXPECT_TRUE(fs::is_empty(dir_));
  const std::string nodir = (dir_ / "no/such/dir/g.yaml").string();
  EXPECT_EQ(errorOf([&] { config::exportGains(defaults_, fis, nodir, ""); }),
            (dir_ / "no/such/dir/g.fis").string() + ": cannot open for writing");
}

TEST(GainsJson, CompactObjectWithTheElevenKeysInOrder) {
  const control::GainSet g = awkwardGains();
  const std::string text = config::gainsJson(g);
  EXPECT_EQ(text.find(' '), std::string::npos) << text;
  EXPECT_EQ(text.rfind("{\"kp\":", 0), 0u) << text;
  const auto j = nlohmann::ordered_json::parse(text);
  ASSERT_EQ(j.size(), control::kGainNames.size());
  std::size_t i = 0;
  for (const auto& [key, value] : j.items()) {
    SCOPED_TRACE(key);
    EXPECT_EQ(key, control::kGainNames[i++]);
    EXPECT_EQ(value.get<double>(), control::gainValue(g, key));
  }
  EXPECT_EQ(config::gainsJson(control::GainSet{}),
            R"({"kp":9.0,"ki":2.0,"kd":3.0,"ke":0.9,"kec":0.1,"k1":3.0,"k2":1.0,"k3":1.0,"a1":-1.0,"a2":-1.2,"a3":-0.5})");
}

}  // namespace
