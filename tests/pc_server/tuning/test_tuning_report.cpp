// Tuning reports (pc_server/tuning/tuning_report.hpp): PID / fuzzy-PID (the
// paper's gains) / changed gains compared on the paper's circle with the
// repo's configs, the console table, and a session directory with every file
// (JSON parsed, gains read back), with and without gnuplot.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "pc_server/tuning/tuning_report.hpp"
#include "shared/config/control_config.hpp"
#include "shared/config/gains_file.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/fuzzy/fis_reader.hpp"
#include "sim/robot_plant.hpp"
#include "tests/support/paths.hpp"
#include "tests/support/process.hpp"
#include "tests/pc_server/tuning/paper_gains.hpp"

using namespace inspect;
using namespace inspect::tuning;
using control::WheelControl;
namespace fs = std::filesystem;

namespace {


TuneSetup repoSetup() {
  TuneSetup s;
  s.robot = config::loadRobotConfigFile(inspect::test::srcPath("config/robot.yaml"));
  s.control = config::loadControlConfigFile(inspect::test::srcPath("config/control.yaml"));
  config::applyRobot(s.control, s.robot);
  s.fis = fuzzy::readFisFile(s.control.fis_path);
  s.plant = sim::nominalPlant(s.robot);
  s.reference.kind = TuneReference::Kind::kCircle;  // the paper's 3.5 m circle, one lap
  s.plant_variations = 2;
  s.seeds = 1;
  s.max_evals = 40;
  s.threads = 2;
  return s;
}

using inspect::test::paperGains;

control::GainSet changedGains(const TuneSetup& s) {
  control::GainSet g = paperGains(s);
  g.fuzzy.base.kp = 14.0;
  g.fuzzy.base.ki = 3.5;
  g.fuzzy.ke = 1.3;
  g.aux.a2 = -2.0;
  g.aux.a3 = -1.1;
  return g;
}

bool isPng(const fs::path& p) { return inspect::test::readFile(p).rfind("\x89PNG\r\n\x1a\n", 0) == 0; }

// One comparison for every test (the closed-loop runs are the slow part).
class TuningReportTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    setup_ = new TuneSetup(repoSetup());
    tuner_ = new Tuner(*setup_);
    const control::GainSet paper = paperGains(*setup_);
    comparison_ = new Comparison(compareControllers(*tuner_, {{"PID", WheelControl::kPid, paper},
                                                              {"fuzzy-PID (paper)", WheelControl::kFuzzyPid, paper},
                                                              {"fuzzy-PID (changed)", WheelControl::kFuzzyPid,
                                                               changedGains(*setup_)}}));
    // A result as the tuner would leave it: the paper's gains improved to the changed set.
    result_ = new TuneResult;
    result_->initial = paper;
    result_->best = changedGains(*setup_);
    result_->initial_eval = comparison_->rows[1].eval;
    result_->best_eval = comparison_->rows[2].eval;
    result_->evals = 6;
    result_->wall_s = 1.25;
    result_->algorithm = "GN_CRS2_LM + LN_BOBYQA";
    const double c0 = result_->initial_eval.cost, c1 = result_->best_eval.cost;
    result_->best_cost_history = {c0, c0, (c0 + c1) / 2, (c0 + c1) / 2, (c0 + 3 * c1) / 4, c1};
  }
  static void TearDownTestSuite() {
    delete result_;
    delete comparison_;
    delete tuner_;
    delete setup_;
  }
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("tuning_report_test_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static TuneSetup* setup_;
  static Tuner* tuner_;
  static Comparison* comparison_;
  static TuneResult* result_;
  fs::path dir_;
};
TuneSetup* TuningReportTest::setup_ = nullptr;
Tuner* TuningReportTest::tuner_ = nullptr;
Comparison* TuningReportTest::comparison_ = nullptr;
TuneResult* TuningReportTest::result_ = nullptr;

TEST_F(TuningReportTest, ComparesEveryCaseOnTheTunersReferenceAndPlant) {
  const Comparison& c = *comparison_;
  EXPECT_EQ(c.reference, setup_->reference.describe());
  EXPECT_NE(c.plant_description.find("time constant 0.2 s"), std::string::npos) << c.plant_description;
  ASSERT_EQ(c.rows.size(), 3u);
  EXPECT_EQ(c.rows[0].label, "PID");
  EXPECT_EQ(c.rows[0].wheel_control, WheelControl::kPid);
  for (const auto& row : c.rows) {
    SCOPED_TRACE(row.label);
    EXPECT_EQ(row.eval.scenarios, 2);
    EXPECT_TRUE(std::isfinite(row.eval.cost));
    EXPECT_GT(row.eval.cost, 0.0);
    // The nominal trace is the whole lap (2 pi 3.5 m at 0.5 m/s = 44 s), sampled every tick.
    ASSERT_GT(row.trace.samples.size(), 4000u);
    EXPECT_NEAR(row.trace.metrics.duration_s, 43.98, 0.05);
    EXPECT_GT(row.trace.metrics.max_pos_err_m, 0.0);
    EXPECT_LT(row.trace.metrics.max_pos_err_m, 0.5);
    EXPECT_GE(row.eval.worst.max_pos_err_m, row.trace.metrics.max_pos_err_m * 0.5);
  }
  // Different controllers and gains give different runs.
  EXPECT_NE(c.rows[0].trace.metrics.rms_pos_err_m, c.rows[1].trace.metrics.rms_pos_err_m);
  EXPECT_NE(c.rows[1].eval.cost, c.rows[2].eval.cost);
}

TEST_F(TuningReportTest, TableHasAColumnPerCaseAndEveryMetric) {
  const std::string table = comparisonTable(*comparison_);
  std::vector<std::string> lines;
  std::istringstream in(table);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  ASSERT_GE(lines.size(), 3u) << table;
  EXPECT_NE(lines[0].find(comparison_->reference), std::string::npos) << table;
  // The header line names the three cases in order.
  const std::string& header = lines[2];
  const auto p0 = header.find("PID"), p1 = header.find("fuzzy-PID (paper)"), p2 = header.find("fuzzy-PID (changed)");
  ASSERT_NE(p0, std::string::npos) << table;
  ASSERT_NE(p1, std::string::npos) << table;
  ASSERT_NE(p2, std::string::npos) << table;
  EXPECT_LT(p0, p1);
  EXPECT_LT(p1, p2);
  const char* metrics[] = {"max position error (m)",   "RMS position error (m)",       "max angle error (rad)",
                           "RMS angle error (rad)",    "position convergence (s)",     "angle convergence (s)",
                           "control effort (rad^2/s)", "saturation time (s)",          "worst max position error (m)",
                           "worst max angle error (rad)", "cost (mean + worst scenario)"};
  for (const char* m : metrics) {
    SCOPED_TRACE(m);
    const auto it = std::find_if(lines.begin(), lines.end(), [&](const std::string& l) { return l.rfind(m, 0) == 0; });
    ASSERT_NE(it, lines.end()) << table;
    // Three cells after the label, each a number or "not conv.".
    std::string rest = it->substr(std::string(m).size());
    std::size_t pos = 0;
    while ((pos = rest.find("not conv.")) != std::string::npos) rest.replace(pos, 9, "nan");
    std::istringstream cells(rest);
    std::vector<std::string> v;
    for (std::string cell; cells >> cell;) v.push_back(cell);
    EXPECT_EQ(v.size(), 3u) << *it;
  }
  EXPECT_NE(table.find("-- over 2 scenario(s)"), std::string::npos) << table;
}

TEST_F(TuningReportTest, SessionDirectoryHasEveryFile) {
  const auto files = writeTuningSession(dir_.string(), *setup_, *result_, *comparison_, setup_->fis);
  EXPECT_EQ(files.dir, dir_.string());
  const char* expected[] = {"summary.md",         "results.json",
                            "gains_tuned.yaml",   "gains_tuned.fis",
                            "traces.csv",         "fig20_position_error.png",
                            "fig20_angle_error.png", "trajectory.png",
                            "cost_history.png"};
  const bool have_gnuplot = std::system("command -v gnuplot > /dev/null 2>&1") == 0;
  for (const char* f : expected) {
    SCOPED_TRACE(f);
    const fs::path p = dir_ / f;
    const bool png = std::string(f).ends_with(".png");
    if (png && !have_gnuplot) continue;  // covered by WithoutGnuplot...
    ASSERT_TRUE(fs::exists(p));
    EXPECT_GT(fs::file_size(p), 100u);
    EXPECT_NE(std::find(files.files.begin(), files.files.end(), p.string()), files.files.end());
    if (png) {
      EXPECT_TRUE(isPng(p));
    }
  }
  if (have_gnuplot) {
    EXPECT_TRUE(files.notes.empty()) << files.notes.front();
    for (const auto& e : fs::directory_iterator(dir_)) EXPECT_NE(e.path().extension(), ".gp") << e.path();
  }

  // results.json parses and has the rows and the history.
  const auto j = nlohmann::json::parse(inspect::test::readFile(dir_ / "results.json"));
  ASSERT_EQ(j["comparison"].size(), 3u);
  EXPECT_EQ(j["comparison"][0]["label"], "PID");
  EXPECT_EQ(j["comparison"][0]["controller"], "pid");
  EXPECT_EQ(j["comparison"][2]["label"], "fuzzy-PID (changed)");
  EXPECT_EQ(j["comparison"][2]["gains"]["kp"].get<double>(), 14.0);
  EXPECT_EQ(j["comparison"][1]["cost"].get<double>(), comparison_->rows[1].eval.cost);
  EXPECT_EQ(j["comparison"][1]["table"]["max_position_error_m"].get<double>(),
            comparison_->rows[1].trace.metrics.max_pos_err_m);
  EXPECT_EQ(j["comparison"][1]["scenarios"], 2);
  EXPECT_EQ(j["best_cost_history"].size(), result_->best_cost_history.size());
  EXPECT_EQ(j["best"]["cost"].get<double>(), result_->best_eval.cost);
  EXPECT_EQ(j["evals"], 6);
  EXPECT_EQ(j["cancelled"], false);
  EXPECT_EQ(j["algorithm"], "GN_CRS2_LM + LN_BOBYQA");
  EXPECT_EQ(j["params"].size(), setup_->params.size());
  EXPECT_EQ(j["params"][0]["name"], "kp");
  EXPECT_EQ(j["params"][0]["lower"].get<double>(), defaultTuneBounds("kp").first);
  EXPECT_EQ(j["scenarios"]["count"], 2);
  EXPECT_EQ(j["plant"]["left"]["time_constant_s"].get<double>(), setup_->plant.left.time_constant_s);

  // The tuned gains read back exactly, with the fuzzy system they belong to.
  fuzzy::Fis fis;
  const auto back = config::importGains((dir_ / "gains_tuned.yaml").string(), control::GainSet{}, &fis);
  EXPECT_TRUE(control::sameGains(back.gains, result_->best));
  EXPECT_EQ(fis, setup_->fis);

  // summary.md: set-up, the comparison table, initial vs best gains, the plots.
  const std::string md = inspect::test::readFile(dir_ / "summary.md");
  const auto [kp_lo, kp_hi] = defaultTuneBounds("kp");
  char kp_row[96];
  std::snprintf(kp_row, sizeof kp_row, "| kp | %g | %g | 9 | 14 |", kp_lo, kp_hi);
  for (const std::string& s : {std::string("Reference: ") + comparison_->reference, std::string("Plant tuned for: "),
                              std::string("GN_CRS2_LM + LN_BOBYQA"), std::string("not cancelled"),
                              std::string(kp_row), std::string("| a2 | -1.2 | -2 | fixed |"),
                              comparisonTable(*comparison_), std::string("Cost weights")})
    EXPECT_NE(md.find(s), std::string::npos) << s << "\n---\n" << md;
  if (have_gnuplot) {
    EXPECT_NE(md.find("![fig20_position_error.png](fig20_position_error.png)"), std::string::npos);
  }

  // traces.csv: a header and one line a tick.
  const std::string csv = inspect::test::readFile(dir_ / "traces.csv");
  EXPECT_EQ(csv.rfind("t_s,ref_x_m,ref_y_m,PID_x_m,PID_y_m,PID_pos_err_m,PID_ang_err_rad,fuzzy_PID__paper__x_m", 0), 0u)
      << csv.substr(0, 200);
  EXPECT_EQ(static_cast<std::size_t>(std::count(csv.begin(), csv.end(), '\n')),
            comparison_->rows[0].trace.samples.size() + 1);
}

TEST_F(TuningReportTest, WithoutGnuplotKeepsTheDataAndSaysSo) {
  // No gnuplot on the PATH: the plots' scripts (with their data) stay, the rest is written.
  const fs::path empty_bin = dir_.string() + "_bin";
  fs::create_directories(empty_bin);
  const char* old = std::getenv("PATH");
  const std::string saved = old ? old : "";
  ::setenv("PATH", empty_bin.c_str(), 1);
  SessionFiles files;
  try {
    files = writeTuningSession(dir_.string(), *setup_, *result_, *comparison_, setup_->fis);
  } catch (...) {
    ::setenv("PATH", saved.c_str(), 1);
    fs::remove_all(empty_bin);
    throw;
  }
  ::setenv("PATH", saved.c_str(), 1);
  fs::remove_all(empty_bin);

  ASSERT_EQ(files.notes.size(), 4u);
  EXPECT_NE(files.notes[0].find("fig20_position_error.png not drawn: gnuplot failed"), std::string::npos)
      << files.notes[0];
  EXPECT_NE(files.notes[0].find("fig20_position_error.png.gp"), std::string::npos) << files.notes[0];
  for (const char* f : {"fig20_position_error.png", "fig20_angle_error.png", "trajectory.png", "cost_history.png"}) {
    SCOPED_TRACE(f);
    EXPECT_FALSE(fs::exists(dir_ / f));
    EXPECT_TRUE(fs::exists(dir_ / (std::string(f) + ".gp")));
  }
  for (const char* f : {"summary.md", "results.json", "gains_tuned.yaml", "gains_tuned.fis", "traces.csv"})
    EXPECT_TRUE(fs::exists(dir_ / f)) << f;
  const std::string md = inspect::test::readFile(dir_ / "summary.md");
  const auto [kp_lo, kp_hi] = defaultTuneBounds("kp");
  char kp_row[96];
  std::snprintf(kp_row, sizeof kp_row, "| kp | %g | %g | 9 | 14 |", kp_lo, kp_hi);
  EXPECT_NE(md.find("No plots were drawn."), std::string::npos) << md;
  EXPECT_NE(md.find("trajectory.png not drawn"), std::string::npos) << md;
  const auto j = nlohmann::json::parse(inspect::test::readFile(dir_ / "results.json"));
  EXPECT_EQ(j["notes"].size(), 4u);
  EXPECT_TRUE(j["plots"].empty());
}

TEST_F(TuningReportTest, UnwritableDirectoryThrows) {
  std::ofstream(dir_.string() + "_file") << "x";  // a file where the directory should go
  EXPECT_THROW(writeTuningSession(dir_.string() + "_file/session", *setup_, *result_, *comparison_, setup_->fis),
               std::runtime_error);
  fs::remove(dir_.string() + "_file");
}

}  // namespace
