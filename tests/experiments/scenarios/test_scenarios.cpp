// The scenario suite in-process: the robot's decision core against the
// simulated world (experiments/scenarios). The strategy must pass every scenario; the
// baselines must behave as their definitions say; the figures must be
// reproducible; a bad suite file must be refused with a clear message.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <map>

#include "experiments/scenarios/scenario.hpp"
#include "tests/support/paths.hpp"

using namespace inspect;
using behavior::SpeedPolicy;

namespace {

std::string src(const std::string& rel) { return inspect::test::srcPath(rel); }

const sim::ScenarioContext& context() {
  static const sim::ScenarioContext ctx = sim::loadScenarioContext(
      src("config/robot.yaml"), src("config/control.yaml"), src("config/behavior.yaml"));
  return ctx;
}

const std::vector<sim::ScenarioSpec>& suite() {
  static const auto s = sim::loadSuiteFile(src("config/scenarios/suite.yaml"));
  return s;
}

// Each scenario x policy is run once and shared by the tests.
const sim::RunMetrics& run(const std::string& name, SpeedPolicy p, bool people = true) {
  static std::map<std::tuple<std::string, SpeedPolicy, bool>, sim::RunMetrics> cache;
  const auto key = std::make_tuple(name, p, people);
  auto it = cache.find(key);
  if (it == cache.end()) {
    for (const auto& s : suite())
      if (s.name == name) it = cache.emplace(key, sim::runScenario(s, context(), {p, people, 1, false}).metrics).first;
  }
  if (it == cache.end()) throw std::runtime_error("no scenario " + name);
  return it->second;
}

class Strategy : public ::testing::TestWithParam<std::string> {};

}  // namespace

TEST(ScenarioSuite, HasThePapersAndTheIssuesScenarios) {
  std::vector<std::string> names;
  for (const auto& s : suite()) names.push_back(s.name);
  for (const char* n : {"crossing", "encountering", "leading", "confronting", "circle_encountering", "warehouse",
                        "narrow_aisle"})
    EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
}

TEST_P(Strategy, SucceedsWithoutCollisionOrIntimateZone) {
  const auto& m = run(GetParam(), SpeedPolicy::kFuzzy);
  std::printf("%s: time to goal %.2f s, min person %.2f m, personal zone %.2f s, stop %.2f s, accuracy %.2f\n",
              GetParam().c_str(), m.time_to_goal_s, m.min_person_m, m.personal_s, m.stop_s, m.pattern_accuracy);
  EXPECT_TRUE(m.success) << m.failure;
  EXPECT_EQ(m.person_collisions, 0u);
  EXPECT_EQ(m.wall_collisions, 0u);
  EXPECT_EQ(m.intimate_s, 0.0);
  EXPECT_GT(m.min_gap_m, 0.1);  // at least 10 cm between the bodies
  EXPECT_GE(m.detect_s, 0.0) << "the robot never noticed anybody";
  EXPECT_LT(m.min_speed_factor, 1.0) << "the strategy never slowed down for anybody";
}

INSTANTIATE_TEST_SUITE_P(AllScenarios, Strategy,
                         ::testing::Values("crossing", "encountering", "leading", "confronting",
                                           "circle_encountering", "warehouse", "narrow_aisle"),
                         [](const auto& info) { return info.param; });

TEST(ScenarioSuite, PlainTrackingNeverSlowsForPeople) {
  for (const char* n : {"crossing", "encountering", "leading", "confronting"}) {
    const auto& m = run(n, SpeedPolicy::kNone);
    const auto& fz = run(n, SpeedPolicy::kFuzzy);
    EXPECT_EQ(m.min_speed_factor, 1.0) << n;  // Eq 9 never applied
    EXPECT_TRUE(m.completed) << n;
    // Only the obstacle stop (a person within 0.9 m straight ahead) can cost it time.
    EXPECT_LT(m.time_to_goal_s, fz.time_to_goal_s) << n;
    EXPECT_LT(m.stop_s, 0.0) << n;  // and it never came to a stop
  }
}

TEST(ScenarioSuite, StopAndWaitStopsAndLosesMoreTimeThanTheStrategy) {
  for (const char* n : {"encountering", "confronting", "leading"}) {
    const auto& sw = run(n, SpeedPolicy::kStopAndWait);
    const auto& fz = run(n, SpeedPolicy::kFuzzy);
    EXPECT_GE(sw.stop_s, 0.0) << n;  // the baseline always comes to a stop
    EXPECT_EQ(sw.min_speed_factor, 0.0) << n;
    EXPECT_GE(sw.time_to_goal_s, fz.time_to_goal_s) << n;
  }
}

TEST(ScenarioSuite, TheStrategyKeepsMoreDistanceThanPlainTracking) {
  for (const char* n : {"leading", "confronting", "circle_encountering"}) {
    EXPECT_GT(run(n, SpeedPolicy::kFuzzy).min_person_m, run(n, SpeedPolicy::kNone).min_person_m) << n;
    EXPECT_LE(run(n, SpeedPolicy::kFuzzy).personal_s, run(n, SpeedPolicy::kNone).personal_s) << n;
  }
}

TEST(ScenarioSuite, LeadingPersonIsClassifiedAsLeading) {
  const auto& m = run("leading", SpeedPolicy::kFuzzy);
  EXPECT_EQ(m.dominant_pattern, "leading");
  EXPECT_GT(m.pattern_accuracy, 0.7);
}

TEST(ScenarioSuite, SameSeedSameFigures) {
  const auto& spec = suite().front();
  const auto a = sim::runScenario(spec, context(), {SpeedPolicy::kFuzzy, true, 7, false}).metrics;
  const auto b = sim::runScenario(spec, context(), {SpeedPolicy::kFuzzy, true, 7, false}).metrics;
  EXPECT_EQ(a.time_to_goal_s, b.time_to_goal_s);
  EXPECT_EQ(a.min_person_m, b.min_person_m);
  EXPECT_EQ(a.path_length_m, b.path_length_m);
  EXPECT_EQ(a.max_jerk_m_s3, b.max_jerk_m_s3);
}

TEST(ScenarioSuite, WithoutPeopleNothingIsDetectedAndTheMetricsSayNobody) {
  const auto& m = run("encountering", SpeedPolicy::kFuzzy, false);
  EXPECT_TRUE(m.success) << m.failure;
  EXPECT_LT(m.min_person_m, 0.0);
  EXPECT_LT(m.detect_s, 0.0);
  EXPECT_EQ(m.min_speed_factor, 1.0);
  EXPECT_NEAR(m.path_length_m, 9.0, 0.2);
}

TEST(ScenarioSuite, TimeLimitIsAFailureWithAReason) {
  auto spec = suite().front();
  spec.time_limit_s = 3.0;
  const auto m = sim::runScenario(spec, context(), {}).metrics;
  EXPECT_FALSE(m.success);
  EXPECT_NE(m.failure.find("not completed within 3 s"), std::string::npos) << m.failure;
}

namespace {
std::string loadError(const std::string& yaml) {
  const std::string path = ::testing::TempDir() + "/bad_suite.yaml";
  std::ofstream(path) << yaml;
  try {
    sim::loadSuiteFile(path);
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(ScenarioSuiteFile, BadFilesAreRefusedNamingTheKey) {
  const std::string world = src("config/worlds/crossing.yaml");
  EXPECT_NE(loadError("scenarios:\n  - {name: a, world: " + world + ", task: {kind: fly}}\n").find("kind"),
            std::string::npos);
  EXPECT_NE(loadError("scenarios:\n  - {name: a, world: " + world + ", task: {kind: line}}\n").find("length_m"),
            std::string::npos);
  EXPECT_NE(loadError("scenarios:\n  - {name: a, world: " + world +
                      ", task: {kind: line, length_m: 2}, expect_pattern: waving}\n")
                .find("expect_pattern"),
            std::string::npos);
  EXPECT_NE(loadError("scenarios:\n  - {name: a, world: " + world + ", task: {kind: line, length_m: 2}, speling: 1}\n")
                .find("speling"),
            std::string::npos);
  EXPECT_NE(loadError("scenarios:\n  - {name: a, world: /nonexistent.yaml, task: {kind: line, length_m: 2}}\n")
                .find("nonexistent"),
            std::string::npos);
  EXPECT_NE(loadError("scenarios:\n  - {name: a, world: " + world + ", task: {kind: goto, points_m: [1, 2, 3]}}\n")
                .find("points_m"),
            std::string::npos);
  EXPECT_NE(loadError("scenarios: []\n").find("none given"), std::string::npos);
}

TEST(ScenarioSuite, TrackingStopsBeforeABoxOnItsPath) {
  // Not a person: the Eq 9 factor does nothing, the front-sonar obstacle stop must.
  sim::ScenarioSpec spec;
  spec.name = "box_on_path";
  spec.world = world::loadWorldText(R"(name: box_on_path
start: {x_m: 0, y_m: 0, theta_rad: 0}
obstacles:
  - {name: box, vertices_m: [3.0, -0.5,  3.6, -0.5,  3.6, 0.5,  3.0, 0.5]}
)",
                                  "box_on_path");
  spec.task.kind = sim::ScenarioTask::Kind::kLine;
  spec.task.length_m = 6.0;
  spec.task.speed_m_s = 0.5;
  spec.time_limit_s = 20;
  const auto r = sim::runScenario(spec, context(), {SpeedPolicy::kFuzzy, true, 1, true});
  EXPECT_FALSE(r.metrics.completed);
  EXPECT_EQ(r.metrics.wall_collisions, 0u);
  ASSERT_FALSE(r.series.empty());
  const double x_end = r.series.back().x_m;
  std::printf("stopped with the axle at x = %.3f m (box face at 3.0 m, body radius 0.35 m)\n", x_end);
  EXPECT_LT(x_end, 3.0 - 0.35 - 0.1);  // at least 10 cm of gap
  EXPECT_GT(x_end, 3.0 - 0.35 - 0.6);  // but it did drive up to it
  EXPECT_LT(std::abs(r.series.back().v_m_s), 0.02);
}
