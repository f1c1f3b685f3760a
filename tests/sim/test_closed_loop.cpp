// Closed-loop trajectory tracking in-process (sim/closed_loop.hpp): the
// paper's circle with each wheel controller, determinism, the noise model, a
// line that ends where it should, and the convergence-time definition.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "shared/config/control_config.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/control/reference_path.hpp"
#include "sim/closed_loop.hpp"
#include "tests/support/paths.hpp"

using namespace inspect;
using control::WheelControl;

namespace {

// The project's defaults: config/robot.yaml and config/control.yaml.
struct Setup {
  config::RobotConfig robot;
  config::ControlConfig control;
  std::shared_ptr<control::FuzzyGainScheduler> scheduler;
};

const Setup& setup() {
  static const Setup s = [] {
    Setup out;
    const std::string root = inspect::test::sourceDir();
    out.robot = config::loadRobotConfigFile(root + "/config/robot.yaml");
    out.control = config::loadControlConfigFile(root + "/config/control.yaml");
    config::applyRobot(out.control, out.robot);
    out.scheduler = config::loadScheduler(out.control);
    return out;
  }();
  return s;
}

sim::ClosedLoopConfig configFor(WheelControl wc) {
  sim::ClosedLoopConfig cfg;
  cfg.robot = setup().robot;
  cfg.tracker = setup().control.tracker;
  cfg.tracker.wheel_control = wc;
  return cfg;
}

// The paper's circle: radius 3.5 m from (0, 0, 0), counter-clockwise, 0.5 m/s.
sim::ClosedLoopResult runCircle(const sim::ClosedLoopConfig& cfg, bool keep_samples = false) {
  return sim::runClosedLoop(cfg, control::makeCircle({0, 0, 0}, 3.5, 0.5), setup().scheduler, keep_samples);
}

}  // namespace

class CircleTracking : public ::testing::TestWithParam<WheelControl> {};

TEST_P(CircleTracking, ErrorsStayBoundedAndConverge) {
  const auto cfg = configFor(GetParam());
  const auto res = runCircle(cfg, true);
  const auto& m = res.metrics;
  EXPECT_NEAR(m.duration_s, 2 * M_PI * 3.5 / 0.5, 0.02);
  EXPECT_LT(m.max_pos_err_m, 0.2);
  EXPECT_LT(m.max_ang_err_rad, 0.2);
  EXPECT_LT(m.final_pos_err_m, 0.02);
  EXPECT_LT(m.rms_pos_err_m, 0.05);
  // Converged well before the end: the error stays in the 0.01 band for the last half lap.
  EXPECT_GT(m.converge_pos_s, 0.0) << "the start transient leaves the band (the robot starts at rest)";
  EXPECT_LT(m.converge_pos_s, m.duration_s / 2);
  EXPECT_LT(m.converge_ang_s, m.duration_s / 2);
  // Samples agree with the metrics.
  ASSERT_FALSE(res.samples.empty());
  double max_pos = 0;
  for (const auto& s : res.samples) max_pos = std::max(max_pos, s.pos_err_m);
  EXPECT_DOUBLE_EQ(max_pos, m.max_pos_err_m);
  EXPECT_DOUBLE_EQ(res.samples.back().pos_err_m, m.final_pos_err_m);
  // The robot went round: a quarter of the way it is near (3.5, 3.5).
  const auto& q = res.samples[res.samples.size() / 4];
  EXPECT_NEAR(q.pose.x_m, 3.5, 0.05);
  EXPECT_NEAR(q.pose.y_m, 3.5, 0.05);
}

TEST_P(CircleTracking, DeterministicForASeed) {
  auto cfg = configFor(GetParam());
  cfg.seed = 7;
  const auto a = runCircle(cfg).metrics, b = runCircle(cfg).metrics;
  EXPECT_EQ(a.max_pos_err_m, b.max_pos_err_m);
  EXPECT_EQ(a.rms_pos_err_m, b.rms_pos_err_m);
  EXPECT_EQ(a.rms_ang_err_rad, b.rms_ang_err_rad);
  EXPECT_EQ(a.command_variation, b.command_variation);
  EXPECT_EQ(a.converge_pos_s, b.converge_pos_s);
  // ...and the seed matters.
  cfg.seed = 8;
  EXPECT_NE(runCircle(cfg).metrics.rms_ang_err_rad, a.rms_ang_err_rad);
}

// RMS of the errors once the start transient is over (second half of the
// lap). Over the whole lap the transient dominates and the noise's effect is
// below 1 % either way (docs/controllers.md).
struct SteadyRms {
  double pos_m = 0;
  double ang_rad = 0;
};
SteadyRms steadyRms(const sim::ClosedLoopResult& r) {
  SteadyRms out;
  const double t_half = r.metrics.duration_s / 2;
  int n = 0;
  for (const auto& s : r.samples) {
    if (s.t_s < t_half) continue;
    out.pos_m += s.pos_err_m * s.pos_err_m;
    out.ang_rad += s.ang_err_rad * s.ang_err_rad;
    ++n;
  }
  out.pos_m = std::sqrt(out.pos_m / n);
  out.ang_rad = std::sqrt(out.ang_rad / n);
  return out;
}

TEST_P(CircleTracking, NoiseOffGivesSmallerSteadyStateErrors) {
  auto cfg = configFor(GetParam());
  const auto noisy = runCircle(cfg, true);
  cfg.noise = false;
  const auto exact = runCircle(cfg, true);
  const SteadyRms n = steadyRms(noisy), e = steadyRms(exact);
  EXPECT_LT(e.pos_m, n.pos_m);
  EXPECT_LT(e.ang_rad, n.ang_rad);
  EXPECT_LT(n.ang_rad, 0.002) << "the heading noise is +-0.002 rad";
  EXPECT_LT(exact.metrics.command_variation, noisy.metrics.command_variation);
}

INSTANTIATE_TEST_SUITE_P(WheelControllers, CircleTracking,
                         ::testing::Values(WheelControl::kDirect, WheelControl::kPid, WheelControl::kFuzzyPid),
                         [](const auto& info) { return std::string(control::toString(info.param)); });

TEST(ClosedLoop, LinePathEndsAtItsEnd) {
  // Once the path is complete the tracker commands zero wheel speed
  // (trajectory_tracker.cpp), so the robot stops on the line but coasts on
  // the motors' lag: r * w * tau beyond the point where the path ended
  // (about v * tau = 0.1 m). If the tracker learns to brake onto the end
  // point, the along-track check becomes |end - 7| < 0.02 m.
  for (const auto wc : {WheelControl::kDirect, WheelControl::kPid, WheelControl::kFuzzyPid}) {
    SCOPED_TRACE(control::toString(wc));
    auto cfg = configFor(wc);
    cfg.extra_time_s = 2.0;  // the reference parks at the end; the robot stops
    const auto res = sim::runClosedLoop(cfg, control::makeLine({1.0, 2.0, M_PI / 2}, 5.0, 0.5), setup().scheduler,
                                        true);
    ASSERT_FALSE(res.samples.empty());
    EXPECT_NEAR(res.metrics.duration_s, 12.0, 0.02);
    const auto& end = res.samples.back();
    EXPECT_NEAR(end.ref.x_m, 1.0, 1e-9);
    EXPECT_NEAR(end.ref.y_m, 7.0, 1e-9);
    EXPECT_NEAR(end.pose.x_m, 1.0, 0.005) << "on the line";
    EXPECT_NEAR(end.pose.theta_rad, M_PI / 2, 0.005);
    EXPECT_NEAR(end.wheel.left_rad_s, 0.0, 1e-3) << "stopped";
    EXPECT_NEAR(end.wheel.right_rad_s, 0.0, 1e-3);
    // The tick at which the path completed: the command drops to zero, the reference is at the end.
    const auto done = std::find_if(res.samples.begin(), res.samples.end(), [](const sim::ClosedLoopSample& s) {
      return s.command.left_rad_s == 0.0 && s.command.right_rad_s == 0.0;
    });
    ASSERT_NE(done, res.samples.end());
    EXPECT_NEAR(done->t_s, 10.0, 0.015);
    EXPECT_NEAR(done->ref.y_m, 7.0, 1e-9);
    EXPECT_NEAR(done->pose.y_m, 7.0, 0.02) << "the robot reached the end with the reference";
    const double coast_m = cfg.robot.geometry.wheel_radius_m * (done->wheel.left_rad_s + done->wheel.right_rad_s) /
                           2 * cfg.robot.motor.time_constant_s;
    EXPECT_NEAR(end.pose.y_m, done->pose.y_m + coast_m, 0.01);
    EXPECT_LT(end.pose.y_m - 7.0, 0.15);
  }
}

// convergenceTime on hand-made series: t = 0.1, 0.2, ...
struct ConvergenceCase {
  std::string name;
  std::vector<double> value;
  double band;
  double expected_s;
};

class ConvergenceTime : public ::testing::TestWithParam<ConvergenceCase> {};

TEST_P(ConvergenceTime, IsTheTimeAfterWhichTheErrorStaysInTheBand) {
  const auto& c = GetParam();
  std::vector<double> t;
  for (std::size_t i = 0; i < c.value.size(); ++i) t.push_back(0.1 * static_cast<double>(i + 1));
  EXPECT_NEAR(sim::convergenceTime(t, c.value, c.band), c.expected_s, 1e-12);
}

INSTANTIATE_TEST_SUITE_P(
    HandMadeSeries, ConvergenceTime,
    ::testing::Values(
        ConvergenceCase{"Empty", {}, 0.01, 0.0},
        ConvergenceCase{"NeverLeavesTheBand", {0.0, 0.005, 0.01, 0.002}, 0.01, 0.0},
        ConvergenceCase{"OnTheBandIsInside", {0.01, 0.01, 0.01}, 0.01, 0.0},
        ConvergenceCase{"FirstSampleOutside", {0.5, 0.0, 0.0, 0.0}, 0.01, 0.2},
        ConvergenceCase{"LastExcursionCounts", {0.5, 0.0, 0.02, 0.0, 0.0}, 0.01, 0.4},
        ConvergenceCase{"NegativeValuesByMagnitude", {0.0, -0.5, 0.0, 0.0}, 0.01, 0.3},
        ConvergenceCase{"DecayingError", {0.08, 0.04, 0.02, 0.011, 0.009, 0.003}, 0.01, 0.5},
        // Outside at the end: the last time is returned, indistinguishable from
        // "entered the band at the last sample" (track_experiment checks the
        // final error to tell them apart).
        ConvergenceCase{"OutsideAtTheEnd", {0.0, 0.0, 0.5}, 0.01, 0.3}),
    [](const auto& info) { return info.param.name; });
