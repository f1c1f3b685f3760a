// Hub-motor plant identification (pc_server/tuning/plant_id.hpp) on runs of
// the simulator's own plant, the MCAP run reader and the plant file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "inspect_robot/v1/link.pb.h"
#include "pc_server/tuning/plant_id.hpp"
#include "shared/config/config_node.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/control/plant_model.hpp"
#include "shared/control/wheel_profile.hpp"
#include "shared/record/mcap_writer.hpp"
#include "sim/robot_plant.hpp"
#include "shared/world/world.hpp"

namespace fs = std::filesystem;
using namespace inspect;
using tuning::IdentifyError;
using tuning::WheelSeries;

namespace {

struct Recording {
  WheelSeries left, right;
  std::vector<uint64_t> robot_time_us;
};

// What robot_client records while playing the standard identification
// profile on `plant`: the real simulator plant stepped at 1 ms behind the
// set-point delay, set-points refreshed by the 100 Hz loop, telemetry at
// 50 Hz with +-2 ms jitter and +-0.01 rad/s uniform speed noise.
Recording recordRun(const control::PlantModel& plant, uint32_t seed, double noise_rad_s = 0.01) {
  const config::RobotConfig robot;
  const world::World world{};
  const sim::RobotPlant motors(robot, world, plant);
  control::SetpointDelay delay(plant.left.dead_time_s, plant.right.dead_time_s);
  const auto profile = control::WheelProfile::standardIdentification(2.0, 5.0);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> jitter_ms(-2, 2);
  std::uniform_real_distribution<double> noise(-noise_rad_s, noise_rad_s);
  const int end_ms = static_cast<int>(std::ceil(profile.duration_s() * 1000.0)) + 500;
  sim::PlantState st;
  control::WheelSpeeds cmd{};
  Recording run;
  int k = 1;
  int next_ms = 20 + jitter_ms(rng);
  for (int ms = 0; ms < end_ms; ++ms) {
    const double t = ms * 1e-3;
    if (ms % 10 == 0) cmd = profile.at(t);  // within the robot's limits; the plant clamps to its own
    if (ms == next_ms) {
      run.robot_time_us.push_back(static_cast<uint64_t>(ms) * 1000u + 123'456'000u);
      for (auto [series, c, w] : {std::tuple{&run.left, cmd.left_rad_s, st.wheel.left_rad_s},
                                  std::tuple{&run.right, cmd.right_rad_s, st.wheel.right_rad_s}}) {
        series->t_s.push_back(t);
        series->command_rad_s.push_back(c);
        series->measured_rad_s.push_back(w + noise(rng));
      }
      next_ms = 20 * ++k + jitter_ms(rng);
    }
    st = motors.step(st, delay.apply(t, cmd), 1e-3).state;
  }
  return run;
}

control::WheelMotorModel motor(double gain, double tau_s, double dead_s, double sat_rad_s = 5.0) {
  return {gain, tau_s, dead_s, sat_rad_s};
}

// The accuracy identification promises on the standard profile.
void expectRecovered(const tuning::WheelFit& fit, const control::WheelMotorModel& truth, const char* wheel) {
  SCOPED_TRACE(wheel);
  EXPECT_NEAR(fit.model.gain, truth.gain, 0.03 * truth.gain);
  EXPECT_NEAR(fit.model.time_constant_s, truth.time_constant_s, 0.10 * truth.time_constant_s);
  EXPECT_NEAR(fit.model.dead_time_s, truth.dead_time_s, 0.015);
  EXPECT_GT(fit.fit_percent, 90.0);
  EXPECT_GT(fit.samples, 1500u);
}

std::string identifyError(const WheelSeries& left, const WheelSeries& right) {
  try {
    tuning::identifyPlant(left, right);
  } catch (const IdentifyError& e) {
    return e.what();
  }
  return "identified";
}

template <typename F>
std::string exceptionText(F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no error";
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

}  // namespace

struct PlantCase {
  const char* name;
  control::PlantModel plant;
};
void PrintTo(const PlantCase& c, std::ostream* os) { *os << c.name; }

class PlantIdRecovers : public ::testing::TestWithParam<PlantCase> {};

TEST_P(PlantIdRecovers, GainTimeConstantAndDeadTime) {
  const auto& truth = GetParam().plant;
  const Recording run = recordRun(truth, 7);
  const auto fit = tuning::identifyPlant(run.left, run.right);
  expectRecovered(fit.left, truth.left, "left");
  expectRecovered(fit.right, truth.right, "right");
  EXPECT_FALSE(fit.left.saturation_observed);
  EXPECT_FALSE(fit.right.saturation_observed);
  EXPECT_DOUBLE_EQ(fit.model.left.saturation_rad_s, 5.0);  // nominal_saturation_rad_s
  EXPECT_NEAR(fit.sample_period_s, 0.02, 0.001);
  EXPECT_NEAR(fit.duration_s, 33.5, 0.1);
  EXPECT_TRUE(fit.warnings.empty()) << fit.warnings.front();
  EXPECT_EQ(control::validatePlant(fit.model), "");
}

INSTANTIATE_TEST_SUITE_P(
    Plants, PlantIdRecovers,
    ::testing::Values(PlantCase{"nominal", {motor(1.0, 0.2, 0.0), motor(1.0, 0.2, 0.0)}},
                      PlantCase{"worn", {motor(0.85, 0.32, 0.04), motor(0.95, 0.28, 0.04)}}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(PlantId, SaturationObservedWhenTheProfileExceedsIt) {
  // The profile's +-2 rad/s steps run into a 1.5 rad/s limit; its +-1 rad/s parts do not.
  const control::PlantModel truth{motor(1.0, 0.2, 0.02, 1.5), motor(0.9, 0.25, 0.02, 1.5)};
  const Recording run = recordRun(truth, 3);
  const auto fit = tuning::identifyPlant(run.left, run.right);
  for (const auto& [w, t, name] :
       {std::tuple{fit.left, truth.left, "left"}, std::tuple{fit.right, truth.right, "right"}}) {
    SCOPED_TRACE(name);
    EXPECT_TRUE(w.saturation_observed);
    EXPECT_NEAR(w.model.saturation_rad_s, 1.5, 0.05);
    expectRecovered(w, t, name);
  }
}

TEST(PlantId, NoisySpeedsAndALongDeadTimeStillGiveThePlant) {
  // +-0.2 rad/s of speed noise (a tenth of the largest step): the output-error
  // fit is not biased by it; the fit figure drops, the parameters do not.
  const control::PlantModel truth{motor(0.85, 0.32, 0.04), motor(0.95, 0.28, 0.2)};
  const Recording run = recordRun(truth, 3, 0.2);
  const auto fit = tuning::identifyPlant(run.left, run.right);
  for (const auto& [w, t, name] :
       {std::tuple{fit.left, truth.left, "left"}, std::tuple{fit.right, truth.right, "right"}}) {
    SCOPED_TRACE(name);
    EXPECT_NEAR(w.model.gain, t.gain, 0.03 * t.gain);
    EXPECT_NEAR(w.model.time_constant_s, t.time_constant_s, 0.10 * t.time_constant_s);
    EXPECT_NEAR(w.model.dead_time_s, t.dead_time_s, 0.015);
    EXPECT_LT(w.fit_percent, 90.0);
    EXPECT_GT(w.rms_error_rad_s, 0.1);  // the noise's own RMS is 0.2 / sqrt(3)
  }
}

TEST(PlantId, WheelsOfDifferentGainsAreReported) {
  const control::PlantModel truth{motor(0.7, 0.2, 0.0), motor(1.0, 0.2, 0.0)};
  const Recording run = recordRun(truth, 5);
  const auto fit = tuning::identifyPlant(run.left, run.right);
  EXPECT_NEAR(fit.model.left.gain, 0.7, 0.02);
  ASSERT_EQ(fit.warnings.size(), 1u);
  EXPECT_TRUE(contains(fit.warnings[0], "gains differ by more than 20 %")) << fit.warnings[0];
}

TEST(PlantId, ALinkGapOfOneSecondStillIdentifies) {
  const control::PlantModel truth{motor(0.85, 0.32, 0.04), motor(0.95, 0.28, 0.04)};
  Recording run = recordRun(truth, 11);
  // Drop every sample in [10, 11) s: in the middle of the chirp.
  for (auto* s : {&run.left, &run.right}) {
    WheelSeries kept;
    for (std::size_t i = 0; i < s->t_s.size(); ++i) {
      if (s->t_s[i] >= 10.0 && s->t_s[i] < 11.0) continue;
      kept.t_s.push_back(s->t_s[i]);
      kept.command_rad_s.push_back(s->command_rad_s[i]);
      kept.measured_rad_s.push_back(s->measured_rad_s[i]);
    }
    *s = std::move(kept);
  }
  const auto fit = tuning::identifyPlant(run.left, run.right);
  expectRecovered(fit.left, truth.left, "left");
  expectRecovered(fit.right, truth.right, "right");
  ASSERT_EQ(fit.warnings.size(), 2u);
  EXPECT_TRUE(contains(fit.warnings[0], "left wheel: 1 gap(s) longer than 0.1 s")) << fit.warnings[0];
}

TEST(PlantId, BadInputIsRefusedWithTheReason) {
  const Recording good = recordRun({motor(1.0, 0.2, 0.0), motor(1.0, 0.2, 0.0)}, 1);
  EXPECT_TRUE(contains(identifyError({}, good.right), "left wheel: too few samples (0; at least 50 needed)"));

  WheelSeries idle;
  for (int i = 0; i < 500; ++i) {
    idle.t_s.push_back(i * 0.02);
    idle.command_rad_s.push_back(0.0);
    idle.measured_rad_s.push_back(0.0);
  }
  EXPECT_EQ(identifyError(good.left, idle), "right wheel: no excitation: the command never exceeds 0.2 rad/s");

  WheelSeries backwards = good.left;
  std::swap(backwards.t_s[100], backwards.t_s[101]);
  EXPECT_TRUE(contains(identifyError(backwards, good.right), "left wheel: time goes backwards at sample 101"));

  WheelSeries nan = good.right;
  nan.measured_rad_s[10] = std::nan("");
  EXPECT_EQ(identifyError(good.left, nan), "right wheel: measured_rad_s of sample 10 is not finite");
  WheelSeries nan_t = good.left;
  nan_t.t_s[3] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(identifyError(nan_t, good.right), "left wheel: t_s of sample 3 is not finite");

  WheelSeries short_cmd = good.left;
  short_cmd.command_rad_s.pop_back();
  EXPECT_TRUE(contains(identifyError(short_cmd, good.right),
                       "left wheel: t_s, command_rad_s and measured_rad_s have different lengths"));

  WheelSeries still = good.left;
  std::fill(still.measured_rad_s.begin(), still.measured_rad_s.end(), 0.0);
  EXPECT_TRUE(contains(identifyError(still, good.right), "left wheel: the measured speed never changes"));

  WheelSeries reversed = good.left;
  for (auto& v : reversed.measured_rad_s) v = -v;
  EXPECT_TRUE(
      contains(identifyError(reversed, good.right), "left wheel: the measured speed does not follow the command"));

  tuning::IdentifyOptions bad;
  bad.max_gap_s = 0.0;
  EXPECT_EQ(exceptionText([&] { tuning::identifyPlant(good.left, good.right, bad); }), "options: max_gap_s must be positive");
}

class PlantIdFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("plant_id_test_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string file(const std::string& name, const std::string& text) const {
    const std::string p = (dir_ / name).string();
    std::ofstream(p) << text;
    return p;
  }
  static std::string read(const std::string& p) {
    std::stringstream ss;
    ss << std::ifstream(p).rdbuf();
    return ss.str();
  }

  fs::path dir_;
};

TEST_F(PlantIdFiles, ARecordedRunIsReadAndIdentified) {
  const control::PlantModel truth{motor(0.85, 0.32, 0.04), motor(0.95, 0.28, 0.04)};
  const Recording run = recordRun(truth, 21);
  const std::string path = (dir_ / "run.mcap").string();
  {
    record::McapWriter w;
    w.open(path);
    const auto ch_tm = w.addProtobufChannel(v1::Telemetry::descriptor(), "/telemetry");
    const auto ch_cmd = w.addProtobufChannel(v1::Command::descriptor(), "/command");
    for (std::size_t i = 0; i < run.robot_time_us.size(); ++i) {
      v1::Telemetry tm;
      tm.set_robot_time_us(run.robot_time_us[i]);
      tm.set_cmd_wheel_left_rad_s(run.left.command_rad_s[i]);
      tm.set_wheel_left_rad_s(run.left.measured_rad_s[i]);
      tm.set_cmd_wheel_right_rad_s(run.right.command_rad_s[i]);
      tm.set_wheel_right_rad_s(run.right.measured_rad_s[i]);
      const uint64_t ns = run.robot_time_us[i] * 1000u;
      w.write(ch_tm, ns, ns, tm);
      if (i == 200) w.write(ch_tm, ns, ns, tm);  // a repeat is dropped
      if (i % 100 == 0) {
        v1::Command c;
        c.set_id(i + 1);
        w.write(ch_cmd, ns, ns, c);
      }
    }
    w.close();
  }
  const auto data = tuning::readRunWheelSeries(path);
  EXPECT_EQ(data.telemetry_messages, run.robot_time_us.size() + 1);
  EXPECT_EQ(data.samples_used, run.robot_time_us.size());
  ASSERT_EQ(data.left.t_s.size(), run.left.t_s.size());
  EXPECT_DOUBLE_EQ(data.left.t_s.front(), 0.0);
  EXPECT_NEAR(data.right.t_s.back(), run.right.t_s.back() - run.right.t_s.front(), 1e-9);
  EXPECT_DOUBLE_EQ(data.right.measured_rad_s[300], run.right.measured_rad_s[300]);
  const auto fit = tuning::identifyPlant(data.left, data.right);
  expectRecovered(fit.left, truth.left, "left");
  expectRecovered(fit.right, truth.right, "right");
}

TEST_F(PlantIdFiles, FilesWithoutTelemetryAreRefusedNamingTheFile) {
  const std::string no_tm = (dir_ / "no_telemetry.mcap").string();
  {
    record::McapWriter w;
    w.open(no_tm);
    const auto ch = w.addProtobufChannel(v1::Command::descriptor(), "/command");
    v1::Command c;
    c.set_id(1);
    w.write(ch, 1, 1, c);
    w.close();
  }
  const std::string e1 = exceptionText([&] { tuning::readRunWheelSeries(no_tm); });
  EXPECT_EQ(e1, no_tm + ": no /telemetry channel (channels: /command)");

  const std::string text = file("notes.mcap", "not a recording\n");
  const std::string e2 = exceptionText([&] { tuning::readRunWheelSeries(text); });
  EXPECT_TRUE(contains(e2, text) && contains(e2, "is not an MCAP file")) << e2;

  const std::string missing = (dir_ / "missing.mcap").string();
  EXPECT_TRUE(contains(exceptionText([&] { tuning::readRunWheelSeries(missing); }), missing));
}

TEST_F(PlantIdFiles, PlantFileRoundTripsAndNamesBadKeys) {
  tuning::PlantFit fit;
  fit.left.model = motor(0.853217, 0.318734, 0.041234, 5.0);
  fit.right.model = motor(0.947891, 0.281234, 0.038765, 1.51234);
  fit.right.saturation_observed = true;
  fit.left.fit_percent = 97.25;
  fit.left.rms_error_rad_s = 0.0123;
  fit.left.samples = 1675;
  fit.model = {fit.left.model, fit.right.model};
  fit.duration_s = 33.5;
  fit.sample_period_s = 0.02;
  fit.warnings = {"left wheel: barely excited\n(test)"};
  const std::string source = "runs/2026-11-22 \"spin\"\\run.mcap";
  const std::string text = tuning::plantYaml(fit, source);
  EXPECT_TRUE(contains(text, "# Hub-motor plant identified from runs/2026-11-22")) << text;
  EXPECT_TRUE(contains(text, "#   - left wheel: barely excited (test)")) << text;
  const std::string path = file("plant.yaml", text);

  const control::PlantModel back = tuning::loadPlantFile(path);
  for (const auto& [got, want] : {std::pair{back.left, fit.left.model}, std::pair{back.right, fit.right.model}}) {
    EXPECT_NEAR(got.gain, want.gain, 1e-5);
    EXPECT_NEAR(got.time_constant_s, want.time_constant_s, 1e-5);
    EXPECT_NEAR(got.dead_time_s, want.dead_time_s, 1e-6);
    EXPECT_NEAR(got.saturation_rad_s, want.saturation_rad_s, 1e-5);
  }
  EXPECT_EQ(config::ConfigNode::loadFile(path).string("source", ""), source);

  const auto edited = [&](const std::string& from, const std::string& to) {
    std::string t = read(path);
    const auto at = t.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    t.replace(at, from.size(), to);
    const std::string p = file("edited.yaml", t);
    return exceptionText([&] { tuning::loadPlantFile(p); });
  };
  const std::string edited_path = (dir_ / "edited.yaml").string();
  EXPECT_EQ(edited("gain: 0.853217", "gain: 7"), edited_path + ": plant.left.gain: 7 is out of range [0.2, 5]");
  EXPECT_EQ(edited("saturation_rad_s: 1.51234", "saturation_rad_s: 0"),
            edited_path + ": plant.right.saturation_rad_s: must be in (0, 100]");
  EXPECT_EQ(edited("dead_time_s: 0.041234", "dead_time: 0.041234"),
            edited_path + ": plant.left.dead_time_s: required value is missing");
  EXPECT_EQ(edited("fit:", "fit:\n  colour: red"),
            edited_path + ": fit.colour: unknown key (misspelt, or not used by this program)");
  EXPECT_TRUE(contains(exceptionText([&] { tuning::loadPlantFile((dir_ / "none.yaml").string()); }), "cannot open file"));
  EXPECT_THROW(tuning::loadPlantFile((dir_ / "none.yaml").string()), config::ConfigError);
}

