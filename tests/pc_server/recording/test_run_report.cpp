// The run report on synthetic telemetry: the PNGs (real gnuplot), the
// summary's figures and links, an empty run, a run without tracking or gas,
// gnuplot missing, the decimation of long runs, and the gas maps with alarms,
// walls and leak estimates (world and odometry frames).
// KEEP_TEST_DIRS=1 keeps the reports (under $TMPDIR) for a look.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "pc_server/recording/run_report.hpp"
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

// A methane leak in an 8 m x 6 m room (walls, and a cabinet), inspected on a
// lawn-mower path at 0.4 m/s with the robot's start pose at (1, 1, 0.3 rad)
// in the world, lanes 1.2 m either side of the leak. Channels CH4 (rising,
// the leak: 20 %LEL at 1 m), H2S (clean air) and O2 (falling: displaced near
// the leak). Alarms: CH4 A1 20-45 s, A2 30-38 s, A1
// again from 50 s to the end; an O2 stuck-sensor fault 5-12 s.
constexpr double kLeakX = 5.0, kLeakY = 3.6;
constexpr double kStartX = 1.0, kStartY = 1.0, kStartTheta = 0.3;
constexpr double kInlet = 0.25;

std::pair<double, double> worldToOdom(double x, double y) {
  const double dx = x - kStartX, dy = y - kStartY, c = std::cos(kStartTheta), s = std::sin(kStartTheta);
  return {c * dx + s * dy, -s * dx + c * dy};
}

v1::GasChannelInfo channelInfo(const char* name, const char* gas, const char* unit, double t90, double background,
                               double low, double high, bool falling) {
  v1::GasChannelInfo c;
  c.set_name(name);
  c.set_gas(gas);
  c.set_unit(unit);
  c.set_t90_s(t90);
  c.set_background(background);
  c.set_alarm_low(low);
  c.set_alarm_high(high);
  c.set_falling(falling);
  return c;
}

RunReportInput labRun(bool have_map) {
  RunReportInput in;
  in.run_id = "run_20240601_090000";
  in.robot = "rover1";
  in.name = "lab inspection";
  in.outcome = "completed";
  in.gas_channels = {channelInfo("CH4", "methane", "%LEL", 6, 0, 10, 20, false),
                     channelInfo("H2S", "hydrogen sulfide", "ppm", 8, 0, 5, 10, false),
                     channelInfo("O2", "oxygen", "%vol", 8, 20.9, 19.5, 18.0, true)};
  in.have_map = have_map;
  in.map_name = "lab_room";
  in.start_x_m = kStartX, in.start_y_m = kStartY, in.start_theta_rad = kStartTheta;
  in.gas_inlet_x_m = kInlet;
  in.walls = {{0, 0, 8, 0}, {8, 0, 8, 6}, {8, 6, 0, 6}, {0, 6, 0, 0},  // the room
              {3.0, 5.2, 4.2, 5.2}, {4.2, 5.2, 4.2, 6.0},              // a cabinet's edges
              {5.3, 3.3, 5.3, 3.9}};  // the pipe the leak is on (estimates keep to surfaces)
  auto ch4 = [](double x, double y) {  // K0 plume, lambda 1 m, 12 %LEL at 1 m
    const double r = std::max(std::hypot(x - kLeakX, y - kLeakY), 0.05);
    return 20.0 / std::cyl_bessel_k(0.0, 1.0) * std::cyl_bessel_k(0.0, r);
  };
  const double tau_ch4 = 6 / std::log(10.0), tau8 = 8 / std::log(10.0), dt = 0.02;
  std::mt19937 rng(7);
  std::normal_distribution<double> n01(0.0, 1.0);
  const std::vector<std::pair<double, double>> legs = {{7, 1}, {7, 2.4}, {1, 2.4}, {1, 4.8}, {7, 4.8}};
  double x = kStartX, y = kStartY, heading = 0, t = 0;
  double s_ch4 = ch4(x + kInlet, y), s_o2 = 20.9 - 0.08 * s_ch4;
  auto emit = [&]() {
    v1::Telemetry m;
    m.set_robot_time_us(1'000'000 + static_cast<uint64_t>(std::llround(t * 1e6)));
    const auto [ox, oy] = worldToOdom(x, y);
    m.mutable_pose()->set_x_m(ox);
    m.mutable_pose()->set_y_m(oy);
    m.mutable_pose()->set_theta_rad(std::remainder(heading - kStartTheta, 2 * M_PI));
    m.set_v_m_s(0.4);
    m.set_speed_factor(1.0);
    m.set_nearest_person_m(-1);
    m.add_gas(s_ch4 + 0.3 * n01(rng));
    m.add_gas(0.2 * n01(rng));
    m.add_gas(s_o2 + 0.03 * n01(rng));
    in.telemetry.push_back(m);
  };
  emit();
  for (const auto& [gx, gy] : legs) {
    heading = std::atan2(gy - y, gx - x);
    const int steps = static_cast<int>(std::round(std::hypot(gx - x, gy - y) / 0.4 / dt));
    const double vx = (gx - x) / (steps * dt), vy = (gy - y) / (steps * dt);
    for (int i = 0; i < steps; ++i) {
      x += vx * dt, y += vy * dt, t += dt;
      const double c = ch4(x + kInlet * std::cos(heading), y + kInlet * std::sin(heading));
      s_ch4 += (c - s_ch4) * (1 - std::exp(-dt / tau_ch4));
      s_o2 += (20.9 - 0.08 * c - s_o2) * (1 - std::exp(-dt / tau8));
      emit();
    }
  }
  auto alarm = [&](double at, uint64_t id, uint32_t ch, v1::GasAlarm::Level level, bool active, double value,
                   double threshold) {
    v1::GasAlarm a;
    a.set_id(id);
    a.set_channel(ch);
    a.set_channel_name(in.gas_channels[ch].name());
    a.set_level(level);
    a.set_active(active);
    a.set_value(value);
    a.set_threshold(threshold);
    a.set_unit(in.gas_channels[ch].unit());
    a.set_peak(value);
    if (level == v1::GasAlarm::SENSOR_FAULT) a.set_fault("stuck");
    *a.mutable_pose() = in.telemetry[static_cast<std::size_t>(at / dt)].pose();
    in.gas_alarms.emplace_back(at, a);
  };
  alarm(5, 1, 2, v1::GasAlarm::SENSOR_FAULT, true, 20.9, 0);
  alarm(12, 1, 2, v1::GasAlarm::SENSOR_FAULT, false, 20.9, 0);
  alarm(20, 2, 0, v1::GasAlarm::LOW, true, 10.3, 10);
  alarm(30, 3, 0, v1::GasAlarm::HIGH, true, 20.4, 20);
  alarm(38, 3, 0, v1::GasAlarm::HIGH, false, 17.9, 20);
  alarm(45, 2, 0, v1::GasAlarm::LOW, false, 7.9, 10);
  alarm(50, 4, 0, v1::GasAlarm::LOW, true, 10.6, 10);
  in.events = {{1.0, "inspection started"}};
  return in;
}

const RunReportResult::LeakResult* leakOf(const RunReportResult& r, const std::string& channel) {
  for (const auto& l : r.leaks)
    if (l.channel == channel) return &l;
  return nullptr;
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

  ASSERT_EQ(res.pngs.size(), 6u);
  for (const char* png : {"trajectory.png", "speed_people.png", "tracking_errors.png", "gas.png", "gas_map_gas0.png",
                          "gas_map_gas1.png"}) {
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

TEST_F(RunReport, GasMapsWithAlarmsWallsAndTheLeakEstimate) {
  const RunReportInput in = labRun(true);
  const auto res = writeRunReport(in, dir_.string());
  for (const char* png : {"gas.png", "gas_map_CH4.png", "gas_map_H2S.png", "gas_map_O2.png"}) {
    EXPECT_TRUE(isPng(dir_ / png)) << png;
    EXPECT_FALSE(fs::exists(dir_ / (std::string(png) + ".gp"))) << png;
  }
  EXPECT_EQ(res.pngs.size(), 6u);  // trajectory, speed_people, gas and three maps

  // The leak, in the world frame, inside its 95 % circle; the map's peak near it.
  ASSERT_EQ(res.leaks.size(), 3u);
  const auto* ch4 = leakOf(res, "CH4");
  ASSERT_NE(ch4, nullptr);
  ASSERT_TRUE(ch4->found) << ch4->note;
  const double err = std::hypot(ch4->x_m - kLeakX, ch4->y_m - kLeakY);
  std::printf("CH4 leak estimate (%.2f, %.2f) +- %.2f m, error %.2f m; map peak (%.2f, %.2f)\n", ch4->x_m, ch4->y_m,
              ch4->radius95_m, err, ch4->peak_x_m, ch4->peak_y_m);
  EXPECT_LT(err, 0.5);
  EXPECT_LE(err, ch4->radius95_m);
  EXPECT_LT(std::hypot(ch4->peak_x_m - kLeakX, ch4->peak_y_m - kLeakY), 1.5);  // on a lane, 1.2 m from it
  EXPECT_EQ(ch4->unit, "%LEL");
  EXPECT_GT(ch4->max_value, 10.0);
  const auto* o2 = leakOf(res, "O2");
  ASSERT_NE(o2, nullptr);
  // O2 dips near the leak (displaced) but never below its A1 (19.5 %vol): no
  // source is estimated from it (falling channels are fitted as a deficit:
  // tests/shared/gas LeakEstimator.FallingChannelFitsTheDeficit); its map still shows the dip.
  EXPECT_FALSE(o2->found);
  EXPECT_NE(o2->note.find("never reached A1"), std::string::npos) << o2->note;
  EXPECT_LT(std::hypot(o2->peak_x_m - kLeakX, o2->peak_y_m - kLeakY), 1.5);  // the lowest cell
  const auto* h2s = leakOf(res, "H2S");
  ASSERT_NE(h2s, nullptr);
  EXPECT_FALSE(h2s->found);
  EXPECT_FALSE(h2s->note.empty());

  const std::string md = readFile(res.summary_path);
  for (const char* text :
       {"## Gas", "| CH4 | methane |", "world frame (map lab_room)", "| gas CH4 max |", "| gas O2 min |",
        // alarms with durations, the open one, and time in alarm per level
        "| 20.0 | 45.0 | 25.0 s | CH4 | A1 (low) | 10.3 %LEL | 10 %LEL |", "| 30.0 | 38.0 | 8.0 s | CH4 | A2 (high) |",
        "| 50.0 | - | still active at end (", "| 5.0 | 12.0 | 7.0 s | O2 | sensor fault: stuck |",
        "| CH4 | A2 (high) | 1 | 8.0 s |", "| O2 | sensor fault | 1 | 7.0 s |", "(still active at end) |",
        // the estimates and the maps
        "**CH4**: leak source at (", "**H2S**: no source estimate: ", "(gas_map_CH4.png)", "(gas_map_O2.png)"})
    EXPECT_NE(md.find(text), std::string::npos) << text << "\n" << md;
  EXPECT_EQ(md.find("gas_map_CH4.png not drawn"), std::string::npos) << md;
}

TEST_F(RunReport, GasMapsWithoutASiteMapUseTheOdometryFrame) {
  RunReportInput in = labRun(false);
  const auto res = writeRunReport(in, dir_.string());
  EXPECT_TRUE(isPng(dir_ / "gas_map_CH4.png"));
  const auto* ch4 = leakOf(res, "CH4");
  ASSERT_NE(ch4, nullptr);
  ASSERT_TRUE(ch4->found) << ch4->note;
  const auto [ox, oy] = worldToOdom(kLeakX, kLeakY);
  EXPECT_LT(std::hypot(ch4->x_m - ox, ch4->y_m - oy), 0.5);
  const std::string md = readFile(res.summary_path);
  EXPECT_NE(md.find("odometry frame"), std::string::npos) << md;
  EXPECT_EQ(md.find("world frame"), std::string::npos) << md;

  // Unknown channels (no Hello): generic names, still mapped.
  in.gas_channels.clear();
  in.gas_alarms.clear();
  const auto res2 = writeRunReport(in, (dir_ / "unnamed").string());
  EXPECT_TRUE(isPng(dir_ / "unnamed" / "gas_map_gas0.png"));
  ASSERT_EQ(res2.leaks.size(), 3u);
  EXPECT_EQ(res2.leaks[0].channel, "gas0");
  const std::string md2 = readFile(res2.summary_path);
  EXPECT_NE(md2.find("No gas alarms."), std::string::npos) << md2;
  EXPECT_NE(md2.find("| gas channel 0 max |"), std::string::npos) << md2;
}
