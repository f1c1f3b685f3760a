// The run report on synthetic telemetry: the PNGs (real gnuplot), the
// summary's figures and links, an empty run, a run without tracking or gas,
// gnuplot missing, and the decimation of long runs.
// KEEP_TEST_DIRS=1 keeps the reports (under $TMPDIR) for a look.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "pc_server/run_report.hpp"
#include "shared/util/clock.hpp"

using namespace inspect;
using namespace inspect::server;
namespace fs = std::filesystem;

namespace {

std::string readFile(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

bool isPng(const fs::path& p) {
  const std::string data = readFile(p);
  return data.size() > 5000 && data.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0;
}

std::vector<std::string> filesIn(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// 60 s at 50 Hz around a circle of radius 2 m, tracking from 1 s to 59 s with
// a wobbling error; a person approaches to 0.6 m at 30 s and leaves; two gas
// channels peak at 40 s.
RunReportInput circleRun() {
  RunReportInput in;
  in.run_id = "run_20240501_120000";
  in.robot = "rover1";
  in.name = "circle test";
  in.outcome = "completed";
  in.started_utc = "2024-05-01T12:00:00Z";
  in.ended_utc = "2024-05-01T12:01:00Z";
  const double w = 2 * M_PI / 60.0, r = 2.0;
  for (int i = 0; i <= 3000; ++i) {
    const double t = i * 0.02;
    v1::Telemetry m;
    m.set_robot_time_us(5'000'000 + static_cast<uint64_t>(i) * 20'000);
    const bool track = t >= 1.0 && t <= 59.0;
    const double a = w * std::clamp(t, 1.0, 59.0);
    const double err = track ? 0.05 + 0.04 * std::sin(t) : 0.0;
    m.mutable_pose()->set_x_m((r + err) * std::cos(a));
    m.mutable_pose()->set_y_m((r + err) * std::sin(a));
    m.mutable_pose()->set_theta_rad(a + M_PI / 2);
    const double person = (t >= 12 && t <= 48) ? 0.6 + 0.25 * std::abs(t - 30) : -1;
    const double factor = person < 0 ? 1.0 : std::clamp((person - 0.45) / 1.5, 0.2, 1.0);
    m.set_nearest_person_m(person);
    m.set_speed_factor(factor);
    m.set_cmd_v_m_s(track ? r * w * factor : 0.0);
    m.set_v_m_s(track ? r * w * factor * (1 + 0.05 * std::sin(3 * t)) : 0.0);
    m.set_mode(track ? v1::TRACKING : v1::IDLE);
    if (track) {
      m.mutable_reference()->set_x_m(r * std::cos(a));
      m.mutable_reference()->set_y_m(r * std::sin(a));
      m.set_position_error_m(err);
      m.set_angle_error_rad(0.05 + 0.03 * std::cos(2 * t));
    }
    m.add_gas(400 + 600 * std::exp(-std::pow((t - 40) / 4, 2)));
    m.add_gas(5 + 20 * std::exp(-std::pow((t - 40) / 3, 2)));
    in.telemetry.push_back(m);
  }
  in.events = {{1.0, "track started"}, {30.0, "person | close"}, {59.0, "track done"}};
  return in;
}

// Each test writes under its own fresh directory.
class RunReport : public ::testing::Test {
 protected:
  void TearDown() override {
    if (!std::getenv("KEEP_TEST_DIRS")) fs::remove_all(dir_);
  }
  const fs::path dir_ = fs::temp_directory_path() /
                        ("inspect-run-report-" + std::to_string(::getpid()) + "-" + std::to_string(monoNowNs()));
};

}  // namespace

TEST_F(RunReport, CircleRunHasAllPlotsAndFigures) {
  RunReportInput in = circleRun();
  fs::create_directories(dir_ / "run");
  std::ofstream(dir_ / "run" / "run.mcap") << "x";
  in.files = {(dir_ / "run" / "run.mcap").string()};
  const auto res = writeRunReport(in, (dir_ / "run" / "report").string());

  ASSERT_EQ(res.pngs.size(), 4u);
  for (const char* png : {"trajectory.png", "speed_people.png", "tracking_errors.png", "gas.png"}) {
    EXPECT_TRUE(isPng(dir_ / "run" / "report" / png)) << png;
    EXPECT_FALSE(fs::exists(dir_ / "run" / "report" / (std::string(png) + ".gp"))) << png;
  }
  const std::string md = readFile(res.summary_path);
  EXPECT_NE(md.find("# Run report: circle test"), std::string::npos) << md;
  EXPECT_NE(md.find("run_20240501_120000"), std::string::npos);
  EXPECT_NE(md.find("Outcome: completed"), std::string::npos);
  EXPECT_NE(md.find("| duration | 60.0 s |"), std::string::npos) << md;
  EXPECT_NE(md.find("| min distance to people | 0.60 m |"), std::string::npos) << md;
  EXPECT_NE(md.find("| tracking max position error | 0.090 m |"), std::string::npos) << md;
  EXPECT_NE(md.find("| tracking rms position error |"), std::string::npos);
  EXPECT_NE(md.find("| gas channel 0 max | 1000 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| gas channel 1 max | 25 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 30.0 | person \\| close |"), std::string::npos) << md;
  for (const char* link : {"(trajectory.png)", "(speed_people.png)", "(tracking_errors.png)", "(gas.png)",
                           "[run.mcap](../run.mcap)"})
    EXPECT_NE(md.find(link), std::string::npos) << link << "\n" << md;
  EXPECT_EQ(md.find("not drawn"), std::string::npos) << md;
}

TEST_F(RunReport, EmptyRunGivesOnlyTheSummary) {
  RunReportInput in;
  in.run_id = "run_empty";
  const auto res = writeRunReport(in, dir_.string());
  EXPECT_TRUE(res.pngs.empty());
  EXPECT_EQ(filesIn(dir_), std::vector<std::string>{"summary.md"});
  const std::string md = readFile(res.summary_path);
  EXPECT_NE(md.find("no telemetry"), std::string::npos) << md;
  EXPECT_NE(md.find("No events."), std::string::npos) << md;
}

TEST_F(RunReport, WithoutTrackingOrGasThosePlotsAreSkipped) {
  RunReportInput in;
  in.run_id = "run_idle";
  for (int i = 0; i < 100; ++i) {
    v1::Telemetry m;
    m.set_robot_time_us(static_cast<uint64_t>(i) * 100'000);
    m.mutable_pose()->set_x_m(0.01 * i);
    m.set_v_m_s(0.1);
    m.set_speed_factor(1.0);
    m.set_nearest_person_m(-1);
    in.telemetry.push_back(m);
  }
  const auto res = writeRunReport(in, dir_.string());
  EXPECT_EQ(res.pngs.size(), 2u);
  EXPECT_EQ(filesIn(dir_), (std::vector<std::string>{"speed_people.png", "summary.md", "trajectory.png"}));
  const std::string md = readFile(res.summary_path);
  EXPECT_NE(md.find("tracking_errors.png not drawn: no TRACKING telemetry"), std::string::npos) << md;
  EXPECT_NE(md.find("gas.png not drawn: no gas values"), std::string::npos) << md;
  EXPECT_NE(md.find("| min distance to people | nobody seen |"), std::string::npos) << md;
}

TEST_F(RunReport, WithoutGnuplotTheSummarySaysWhy) {
  const std::string path = std::getenv("PATH") ? std::getenv("PATH") : "";
  ::setenv("PATH", (dir_ / "no-bin").c_str(), 1);
  RunReportInput in = circleRun();
  in.telemetry.resize(50);
  const auto res = writeRunReport(in, dir_.string());
  ::setenv("PATH", path.c_str(), 1);
  EXPECT_TRUE(res.pngs.empty());
  EXPECT_EQ(filesIn(dir_), std::vector<std::string>{"summary.md"});
  const std::string md = readFile(res.summary_path);
  EXPECT_NE(md.find("No plots were drawn."), std::string::npos) << md;
  EXPECT_NE(md.find("trajectory.png not drawn: gnuplot"), std::string::npos) << md;
  EXPECT_NE(md.find("| duration |"), std::string::npos) << md;
}

TEST_F(RunReport, LongRunsAreDecimated) {
  const auto idx = sampleIndices(20'001, 5000);
  ASSERT_LE(idx.size(), 5000u);
  EXPECT_GE(idx.size(), 4000u);
  EXPECT_EQ(idx.front(), 0u);
  EXPECT_EQ(idx.back(), 20'000u);
  for (std::size_t i = 1; i < idx.size(); ++i) ASSERT_LT(idx[i - 1], idx[i]);
  EXPECT_EQ(sampleIndices(10, 5000).size(), 10u);
  EXPECT_EQ(sampleIndices(10, 2), (std::vector<std::size_t>{0, 9}));
  EXPECT_TRUE(sampleIndices(0, 5000).empty());
}
