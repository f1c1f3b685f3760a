// Simulated gas: the dispersion model against the analytic free-space
// solution, walls, airflow and mass balance; the sensor model (t90, noise,
// cross-sensitivity, faults, MCU fault flag); world-file errors; and the
// gas_lab world's steady plumes along the inspection route.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "shared/config/robot_config.hpp"
#include "shared/serial/frame_codec.hpp"
#include "sim/gas_model.hpp"
#include "sim/gas_sensor.hpp"
#include "sim/simulation.hpp"
#include "sim/mcu_sim/truth_log.hpp"
#include "shared/world/world.hpp"
#include "tests/sim/world_text.hpp"
#include "tests/support/paths.hpp"
#include "tests/sim/sensor_frames.hpp"

using namespace inspect;
using namespace inspect::sim;
using namespace inspect::world;

namespace {

using inspect::test::worldOf;


// A closed square room of half-size `half_m` round the origin, plus `gas` lines (indented 2).
std::string room(double half_m, const std::string& gas, const std::string& extra = "") {
  std::ostringstream os;
  os << "walls:\n  - {points_m: [" << -half_m << ", " << -half_m << ", " << half_m << ", " << -half_m << ", " << half_m
     << ", " << half_m << ", " << -half_m << ", " << half_m << "], closed: true}\n"
     << extra << "gas:\n"
     << gas;
  return os.str();
}

// Steady free-space solution of dc/dt = D lap c - k c + q delta: q/(2 pi D) K0(r / sqrt(D/k)).
double besselSolution(double q, double d, double k, double r) {
  return q / (2.0 * std::numbers::pi * d) * std::cyl_bessel_k(0.0, r / std::sqrt(d / k));
}

// A robot with the default gas channels (as config/robot.yaml): CH4, H2S, CO, O2.
config::RobotConfig gasRobot() {
  config::RobotConfig r;
  r.gas = config::defaultGasConfig();
  return r;
}

std::string simError(const std::string& yaml) {
  try {
    Simulation sim(gasRobot(), worldOf(yaml, "gas_world.yaml"), 1);
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

config::GasChannel channel(double t90_s, double noise, double scale = 0.01) {
  config::GasChannel c;
  c.name = "X";
  c.unit = "ppm";
  c.scale = scale;
  c.t90_s = t90_s;
  c.noise = noise;
  return c;
}

}  // namespace

// --- dispersion ---

TEST(GasModel, FreeSpaceSteadyStateIsSymmetricAndMatchesBesselK0) {
  // Source at a cell centre, walls 8 decay lengths away: effectively free space.
  constexpr double q = 5.0, d = 0.05, k = 0.05;
  const World w = worldOf(room(8.0, "  diffusivity_m2_s: 0.05\n  ventilation_per_s: 0.05\n  cell_m: 0.1\n"
                                    "  sources: [{gas: CH4, x_m: 0.05, y_m: 0.05, rate: 5, start_s: -1e5}]\n"), "gas_world.yaml");
  const GasModel g(w);
  ASSERT_EQ(g.gases().size(), 1u);
  const int f = g.field("CH4");
  ASSERT_EQ(f, 0);
  const Vec2 src{0.05, 0.05};
  double prev = std::numeric_limits<double>::infinity();
  for (double r : {0.3, 0.5, 0.7, 1.0, 1.5, 2.0, 2.5, 3.0}) {
    const double east = g.concentration(f, {src.x + r, src.y});
    const double west = g.concentration(f, {src.x - r, src.y});
    const double north = g.concentration(f, {src.x, src.y + r});
    const double south = g.concentration(f, {src.x, src.y - r});
    const double diag = g.concentration(f, {src.x + r / std::sqrt(2.0), src.y + r / std::sqrt(2.0)});
    const double exact = besselSolution(q, d, k, r);
    std::printf("GAS free space r=%.1f m: c=%.4f  K0 solution=%.4f  (%+.2f %%)  diagonal %+.2f %%\n", r, east, exact,
                100.0 * (east / exact - 1.0), 100.0 * (diag / exact - 1.0));
    // The source sits 0.05 m off the room's centre: the far walls' echo differs by ~1e-6.
    EXPECT_NEAR(west / east, 1.0, 1e-5) << r;
    EXPECT_NEAR(north / east, 1.0, 1e-5) << r;
    EXPECT_NEAR(south / east, 1.0, 1e-5) << r;
    EXPECT_NEAR(east / exact, 1.0, 0.03) << "r = " << r;  // >= 3 cells from the source: within 3 %
    EXPECT_NEAR(diag / exact, 1.0, 0.05) << "diagonal r = " << r;  // between cell centres: bilinear error too
    EXPECT_LT(east, prev);
    prev = east;
  }
}

TEST(GasModel, ExplicitStepsConvergeToTheSteadyState) {
  // The steady state solved at construction (SOR) is the fixed point of the time stepping, from
  // diffusion-dominated to advection-dominated air (cell Peclet number u h / D up to 5).
  struct Case {
    const char* params;
    double run_s;  // >= 15 / k
  };
  const Case cases[] = {
      {"  diffusivity_m2_s: 0.05\n  ventilation_per_s: 0.05\n  airflow_m_s: [0.03, -0.01]\n", 300.0},
      {"  diffusivity_m2_s: 0.01\n  ventilation_per_s: 0.2\n  airflow_m_s: [0.5, 0.2]\n", 75.0},
      {"  diffusivity_m2_s: 0.5\n  ventilation_per_s: 0.1\n  airflow_m_s: [0, 0]\n", 150.0},
  };
  for (const auto& c : cases) {
    const std::string gas = std::string(c.params) + "  sources: [{gas: CH4, x_m: -0.5, y_m: 0.3, rate: 4, start_s: ";
    const GasModel steady(worldOf(room(3.0, gas + "-1e5}]\n"), "gas_world.yaml"));
    GasModel run(worldOf(room(3.0, gas + "0}]\n"), "gas_world.yaml"));
    EXPECT_EQ(run.mass(0), 0.0);
    const int n = static_cast<int>(c.run_s / 0.05);
    for (int i = 1; i <= n; ++i) run.advanceTo(i * 0.05);
    for (Vec2 p : {Vec2{-0.5, 0.3}, Vec2{0.5, 0.3}, Vec2{-1.5, -1.0}, Vec2{2.0, 2.0}})
      EXPECT_NEAR(run.concentration(0, p) / steady.concentration(0, p), 1.0, 1e-3) << c.params << p.x << "," << p.y;
  }
}

TEST(GasModel, SteadyFieldsAreLeftAloneUntilALeakStartsOrStops) {
  // Linearity: both leaks together = each alone, whether a field is stepped or left steady.
  const std::string old_leak = "    - {gas: CH4, x_m: -1.0, y_m: 0.5, rate: 3, start_s: -1e5}\n";
  const std::string new_leak = "    - {gas: CH4, x_m: 1.0, y_m: -0.5, rate: 2, start_s: 5, end_s: 12}\n";
  GasModel both(worldOf(room(3.0, "  airflow_m_s: [0.02, 0.01]\n  sources:\n" + old_leak + new_leak), "gas_world.yaml"));
  GasModel first(worldOf(room(3.0, "  airflow_m_s: [0.02, 0.01]\n  sources:\n" + old_leak), "gas_world.yaml"));
  GasModel second(worldOf(room(3.0, "  airflow_m_s: [0.02, 0.01]\n  sources:\n" + new_leak), "gas_world.yaml"));
  EXPECT_TRUE(both.steady(0));
  EXPECT_TRUE(second.steady(0));  // nothing yet
  EXPECT_FALSE(both.steady(1));
  const double m0 = first.mass(0);
  for (int i = 1; i <= 400; ++i) {
    const double t = i * 0.05;
    both.advanceTo(t);
    first.advanceTo(t);
    second.advanceTo(t);
    EXPECT_EQ(both.steady(0), t < 5.0 - 1e-9) << t;
    EXPECT_EQ(second.steady(0), t < 5.0 - 1e-9) << t;
    if (i % 20 == 0) {
      for (Vec2 p : {Vec2{-1.0, 0.5}, Vec2{1.0, -0.5}, Vec2{0.0, 0.0}, Vec2{2.5, 2.5}})
        EXPECT_NEAR(both.concentration(0, p), first.concentration(0, p) + second.concentration(0, p),
                    1e-6 * both.concentration(0, p))
            << t;
    }
  }
  EXPECT_TRUE(first.steady(0));
  EXPECT_EQ(first.mass(0), m0);
  EXPECT_GT(second.mass(0), 1.0);
  // Still steady after the fact: a stepped steady state stays put (to the solver's tolerance).
  GasModel stepped(worldOf(room(3.0, "  airflow_m_s: [0.02, 0.01]\n  sources:\n" + old_leak +
                                       "    - {gas: CH4, x_m: 1.0, y_m: -0.5, rate: 2, start_s: 1e8}\n"), "gas_world.yaml"));
  stepped.advanceTo(1e8 - 1.0);
  EXPECT_TRUE(stepped.steady(0));
  stepped.advanceTo(1e8 + 0.05);
  EXPECT_FALSE(stepped.steady(0));
}

TEST(GasModel, SubstepCountHoldsLongJumps) {
  const GasModel g(worldOf(room(3.0, "  sources: [{gas: CH4, x_m: 0.0, y_m: 0.0, rate: 1, start_s: 0}]\n"), "gas_world.yaml"));
  const double step = GasModel::kStabilityFactor * g.maxStableStepS();
  EXPECT_EQ(g.substeps(0.0), 0);
  EXPECT_EQ(g.substeps(-1.0), 0);
  EXPECT_EQ(g.substeps(std::nan("")), 0);
  EXPECT_EQ(g.substeps(0.5 * step), 1);
  EXPECT_EQ(g.substeps(step), 1);
  EXPECT_EQ(g.substeps(3.5 * step), 4);
  // 1e8 s is more sub-steps than an int holds: counted exactly, not wrapped.
  const std::int64_t n = g.substeps(1e8);
  EXPECT_GT(n, std::int64_t{std::numeric_limits<int>::max()});
  EXPECT_NEAR(static_cast<double>(n), 1e8 / step, 1.0);
  // Beyond any sim time a run can reach: capped, still positive.
  EXPECT_EQ(g.substeps(1e300), std::int64_t{1} << 62);
  EXPECT_EQ(g.substeps(std::numeric_limits<double>::infinity()), std::int64_t{1} << 62);
}

TEST(GasModel, WallBlocksGas) {
  // A 6 m wall 1 m east of the source: behind it the gas must go round the ends.
  const World w = worldOf(room(6.0, "  sources: [{gas: CH4, x_m: 0.05, y_m: 0.05, rate: 5, start_s: -1e5}]\n",
                                "  - {from_m: [1.0, -3.0], to_m: [1.0, 3.0]}\n"), "gas_world.yaml");
  const GasModel g(w);
  const double open = g.concentration(0, {-1.95, 0.05});
  const double behind = g.concentration(0, {2.05, 0.05});
  std::printf("GAS wall: 2 m from the source in the open %.4f, behind the wall %.6f (ratio %.0f)\n", open, behind,
              open / behind);
  EXPECT_LT(behind, 0.01 * open);
  // Interpolation does not reach through the wall: 2 cm either side of it.
  const double front = g.concentration(0, {0.98, 0.05});
  const double back = g.concentration(0, {1.02, 0.05});
  EXPECT_GT(front, 0.3 * g.concentration(0, {0.95, 0.05}));
  EXPECT_LT(back, 0.01 * front);
}

TEST(GasModel, AirflowShiftsThePlumeDownwind) {
  const auto yaml = [](const char* u) {
    return room(6.0, std::string("  airflow_m_s: ") + u +
                         "\n  sources: [{gas: H2S, x_m: 0.05, y_m: 0.05, rate: 5, start_s: -1e5}]\n");
  };
  const GasModel still(worldOf(yaml("[0, 0]"), "gas_world.yaml"));
  const GasModel east(worldOf(yaml("[0.1, 0]"), "gas_world.yaml"));
  const double up = east.concentration(0, {-0.95, 0.05}), down = east.concentration(0, {1.05, 0.05});
  // Analytic: c = q/(2 pi D) exp(u x / 2D) K0(r sqrt(u^2/4D^2 + k/D)): down/up = exp(u r / D) = e^2 at r = 1 m.
  std::printf("GAS airflow 0.1 m/s: 1 m downwind %.4f, 1 m upwind %.4f, ratio %.2f (analytic %.2f); still air %.4f\n",
              down, up, down / up, std::exp(2.0), still.concentration(0, {1.05, 0.05}));
  EXPECT_GT(down / up, 5.0);
  EXPECT_LT(down / up, 9.0);
  EXPECT_NEAR(still.concentration(0, {1.05, 0.05}) / still.concentration(0, {-0.95, 0.05}), 1.0, 1e-5);
  // Crosswind stays symmetric.
  EXPECT_NEAR(east.concentration(0, {0.05, 1.05}) / east.concentration(0, {0.05, -0.95}), 1.0, 1e-5);
}

TEST(GasModel, MassBalanceWithoutVentilation) {
  // Closed room, no removal, a draught pushing the gas into a corner: every emitted unit stays.
  const World w = worldOf(room(2.0, "  ventilation_per_s: 0\n  airflow_m_s: [0.05, 0.02]\n  sources:\n"
                                    "    - {gas: CH4, x_m: -1.0, y_m: 0.5, rate: 2.0}\n"
                                    "    - {gas: CH4, x_m: 1.0, y_m: -0.5, rate: 1.0, start_s: 5, end_s: 12}\n"), "gas_world.yaml");
  GasModel g(w);
  for (int i = 1; i <= 400; ++i) g.advanceTo(i * 0.05);  // 20 s
  const double expected = 2.0 * 20.0 + 1.0 * 7.0;
  std::printf("GAS mass balance: %.6f emitted %.6f\n", g.mass(0), expected);
  EXPECT_NEAR(g.mass(0) / expected, 1.0, 0.01);  // in fact to rounding: every sub-step's emission stays
}

TEST(GasModel, PreIntegratedLeaksCarryTheRightMass) {
  // Closed room with ventilation: total mass obeys dM/dt = q - k M exactly.
  constexpr double q = 3.0, k = 0.05;
  const auto massOf = [](const std::string& times) {
    return GasModel(worldOf(room(3.0, "  sources: [{gas: CO, x_m: 0.3, y_m: 0.2, rate: 3, " + times + "}]\n"), "gas_world.yaml"))
        .mass(0);
  };
  EXPECT_NEAR(massOf("start_s: -1e6") / (q / k), 1.0, 2e-3);  // steady state solved directly
  EXPECT_NEAR(massOf("start_s: -20") / (q / k * (1.0 - std::exp(-k * 20.0))), 1.0, 1e-3);
  EXPECT_NEAR(massOf("start_s: -100, end_s: -10") / (q / k * (1.0 - std::exp(-k * 90.0)) * std::exp(-k * 10.0)), 1.0,
              1e-3);
  EXPECT_EQ(massOf("start_s: -1e6, end_s: -1e5"), 0.0);
  EXPECT_EQ(massOf("start_s: 5"), 0.0);
}

TEST(GasModel, ConcentrationIsZeroInsideObstaclesAndOffTheGrid) {
  const World w = worldOf(room(3.0, "  sources: [{gas: CH4, x_m: 0.0, y_m: 0.45, rate: 5, start_s: -1e5}]\n",
                               "obstacles:\n  - {vertices_m: [-1, -0.3, 1, -0.3, 1, 0.3, -1, 0.3]}\n"), "gas_world.yaml");
  const GasModel g(w);
  EXPECT_GT(g.concentration(0, {0.0, 0.5}), 1.0);
  EXPECT_EQ(g.concentration(0, {0.0, 0.0}), 0.0);
  EXPECT_EQ(g.concentration(0, {0.0, 0.25}), 0.0);
  EXPECT_EQ(g.concentration(0, {50.0, 0.0}), 0.0);
  EXPECT_EQ(g.concentration(1, {0.0, 0.5}), 0.0);  // no such field
  EXPECT_EQ(g.field("H2S"), -1);
  // The obstacle shadows: the far side is much cleaner than the near side at the same distance.
  EXPECT_LT(g.concentration(0, {0.0, -0.55}), 0.2 * g.concentration(0, {0.0, 1.45}));
}

// --- sensors ---

TEST(GasSensor, StepReaches90PercentAtT90) {
  for (double t90 : {2.0, 6.0, 8.0, 30.0}) {
    config::GasConfig cfg;
    cfg.channels.push_back(channel(t90, 0.0));
    GasSensors s(cfg, {}, 1);
    const std::vector<double> zero{0.0}, step{100.0};
    s.settle(zero);
    double t90_seen = -1.0;
    for (int i = 1; i <= 100 * 100 && t90_seen < 0; ++i) {
      s.sample(i * 0.01, 0.01, step);
      if (s.reading(0) >= 90.0) t90_seen = i * 0.01;
    }
    EXPECT_NEAR(t90_seen, t90, 0.05 * t90) << t90;
    // The response itself is the exact first-order lag: 1 - 10^(-t / t90).
    GasSensors e(cfg, {}, 1);
    e.settle(zero);
    for (int i = 1; i <= 50; ++i) e.sample(i * 0.01, 0.01, step);
    EXPECT_NEAR(e.response(0), 100.0 * (1.0 - std::pow(10.0, -0.5 / t90)), 1e-9);
  }
}

TEST(GasSensor, NoiseStandardDeviationMatchesConfig) {
  for (double noise : {0.03, 0.3, 1.0}) {
    config::GasConfig cfg;
    cfg.channels.push_back(channel(6.0, noise));
    GasSensors s(cfg, {}, 42);
    const std::vector<double> v{50.0};
    s.settle(v);
    constexpr int n = 40000;
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < n; ++i) {
      s.sample(i * 0.01, 0.01, v);
      sum += s.reading(0);
      sum2 += s.reading(0) * s.reading(0);
    }
    const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
    const double expected = std::sqrt(noise * noise + 0.01 * 0.01 / 12.0);  // + quantisation
    EXPECT_NEAR(mean, 50.0, 4.0 * noise / std::sqrt(n) + 1e-3) << noise;
    EXPECT_NEAR(sd / expected, 1.0, 0.03) << noise;
  }
}

TEST(GasSensor, QuantisesAndClampsToRawCounts) {
  config::GasConfig cfg;
  cfg.channels.push_back(channel(1.0, 0.0, 0.1));
  GasSensors s(cfg, {}, 1);
  const std::vector<double> v{12.34};
  s.settle(v);
  auto raw = s.sample(0.0, 0.0, v);
  EXPECT_EQ(raw[0], 123);
  EXPECT_NEAR(s.reading(0), 12.3, 1e-9);
  EXPECT_EQ(raw[1], 0);  // slots beyond the configured channels
  EXPECT_EQ(raw[3], 0);
  const std::vector<double> neg{-5.0}, huge{1e9};
  s.settle(neg);
  EXPECT_EQ(s.sample(0.01, 0.01, neg)[0], 0);
  s.settle(huge);
  EXPECT_EQ(s.sample(0.02, 0.01, huge)[0], config::kGasRawMax);
}

TEST(GasSensor, StuckFreezesAndDropoutSendsNoData) {
  config::GasConfig cfg;
  cfg.channels.push_back(channel(1.0, 0.0));
  cfg.channels.push_back(channel(1.0, 0.0));
  GasSensors s(cfg, {{0, GasFaultKind::Stuck, 1.0, 2.0}, {1, GasFaultKind::Dropout, 1.5, 1.8}}, 1);
  const std::vector<double> zero{0.0, 0.0};
  s.settle(zero);
  uint16_t before = 0;
  for (int i = 0; i <= 300; ++i) {
    const double t = i * 0.01;
    const std::vector<double> ramp{10.0 * t, 10.0 * t};
    const auto raw = s.sample(t, 0.01, ramp);
    if (t < 1.0 - 1e-9) before = raw[0];
    if (t >= 1.0 - 1e-9 && t < 2.0 - 1e-9) {
      EXPECT_EQ(raw[0], before) << t;  // frozen at the last reading before the fault
    }
    if (t > 2.05) {
      EXPECT_GT(raw[0], before + 100) << t;  // follows again
    }
    const bool dropped = t >= 1.5 - 1e-9 && t < 1.8 - 1e-9;
    EXPECT_EQ(raw[1] == config::kGasNoData, dropped) << t;
    EXPECT_EQ(std::isnan(s.reading(1)), dropped) << t;
  }
}

// --- in the simulation ---

TEST(GasSimulation, CrossSensitivityAndBackground) {
  // Default channels: CO reads 0.1 x H2S, O2 reads 20.9 - 0.0105 x CH4.
  Simulation sim(gasRobot(),
                 worldOf(room(4.0, "  sources:\n    - {gas: H2S, x_m: 1.0, y_m: 1.0, rate: 5, start_s: -1e5}\n"
                                   "    - {gas: CH4, x_m: -1.0, y_m: -1.0, rate: 20, start_s: -1e5}\n"), "gas_world.yaml"),
                 1);
  for (Vec2 p : {Vec2{1.5, 1.0}, Vec2{0.0, 0.0}, Vec2{-1.3, -0.8}}) {
    const double ch4 = sim.trueConcentration(0, p), h2s = sim.trueConcentration(1, p);
    EXPECT_GT(ch4, 0.0);
    EXPECT_GT(h2s, 0.0);
    EXPECT_NEAR(ch4, sim.gas().concentration(sim.gas().field("CH4"), p), 1e-12);
    EXPECT_NEAR(sim.trueConcentration(2, p), 0.1 * h2s, 1e-12);
    EXPECT_NEAR(sim.trueConcentration(3, p), 20.9 - 0.0105 * ch4, 1e-12);
  }
  EXPECT_TRUE(std::isnan(sim.trueConcentration(4, {0, 0})));
  // No leaks: the background only.
  Simulation clean(gasRobot(), World{}, 1);
  EXPECT_EQ(clean.trueConcentration(0, {0, 0}), 0.0);
  EXPECT_EQ(clean.trueConcentration(3, {0, 0}), 20.9);
}

TEST(GasSimulation, FramesCarryReadingsAndDropoutSetsTheMcuFault) {
  const config::RobotConfig robot = gasRobot();
  struct Rec : SimObserver {
    std::vector<std::string> events;
    int gas_rows = 0;
    void onEvent(double, std::string_view e, std::string_view d) override {
      events.push_back(std::string(e) + " " + std::string(d));
    }
    void onGas(const GasSample& s) override {
      ++gas_rows;
      EXPECT_EQ(s.true_value.size(), 4u);
      EXPECT_EQ(s.reading.size(), 4u);
    }
  } rec;
  Simulation sim(robot,
                 worldOf(room(4.0, "  sources: [{name: v1, gas: CH4, x_m: 0.8, y_m: 0.0, rate: 20, start_s: -1e5}]\n"
                                   "  faults:\n    - {channel: H2S, kind: dropout, start_s: 0.5, end_s: 1.0}\n"
                                   "    - {channel: CO, kind: stuck, start_s: 0.2}\n"), "gas_world.yaml"),
                 3, &rec);
  sim.advanceTo(1500);
  std::vector<uint8_t> tx;
  sim.takeTx(tx);
  const auto frames = inspect::test::decodeSensorFrames(tx);
  ASSERT_EQ(frames.size(), 150u);
  const double ch4_true = sim.trueConcentration(0, sim.gasInlet());
  for (const auto& f : frames) {
    const double t = f.mcu_time_ms / 1000.0;
    const bool dropped = t >= 0.5 - 1e-9 && t < 1.0 - 1e-9;
    EXPECT_EQ(f.gas_raw[1] == config::kGasNoData, dropped) << t;
    EXPECT_EQ((f.faults & serial::kFaultGasSensor) != 0, dropped) << t;
    EXPECT_NEAR(f.gas_raw[0] * 0.01, ch4_true, 5 * 0.3) << t;  // settled at start: no transient
    EXPECT_NEAR(f.gas_raw[3] * 0.01, 20.9 - 0.0105 * ch4_true, 5 * 0.03) << t;
    if (t >= 0.2) {
      EXPECT_EQ(f.gas_raw[2], frames[20].gas_raw[2]) << t;  // CO stuck from 0.2 s
    }
  }
  EXPECT_GT(ch4_true, 10.0);
  EXPECT_EQ(rec.gas_rows, 15);
  auto has = [&](const std::string& s) {
    for (const auto& e : rec.events)
      if (e.rfind(s, 0) == 0) return true;
    return false;
  };
  EXPECT_TRUE(has("gas_channels CH4=%LEL H2S=ppm CO=ppm O2=%vol"));
  EXPECT_TRUE(has("gas_source name=v1 gas=CH4 x=0.800 y=0.000 rate=20"));
  EXPECT_TRUE(has("gas_fault_start channel=H2S kind=dropout"));
  EXPECT_TRUE(has("gas_fault_end channel=H2S kind=dropout"));
  EXPECT_TRUE(has("gas_fault_start channel=CO kind=stuck"));
  EXPECT_FALSE(sim.mcu().faults() & serial::kFaultGasSensor);
}

TEST(GasSimulation, FewerChannelsLeaveTheOtherSlotsZero) {
  config::RobotConfig robot = gasRobot();
  robot.gas.channels.resize(2);  // CH4, H2S
  Simulation sim(robot, World{}, 1);
  sim.advanceTo(100);
  std::vector<uint8_t> tx;
  sim.takeTx(tx);
  const auto frames = inspect::test::decodeSensorFrames(tx);
  ASSERT_EQ(frames.size(), 10u);
  for (const auto& f : frames) {
    EXPECT_EQ(f.gas_raw[2], 0);
    EXPECT_EQ(f.gas_raw[3], 0);
    EXPECT_EQ(f.faults & serial::kFaultGasSensor, 0);
  }
}

TEST(GasSimulation, RobotWithoutGasChannelsSendsZerosAndNoGasRows) {
  struct Rec : SimObserver {
    int gas_rows = 0, gas_events = 0;
    void onGas(const GasSample&) override { ++gas_rows; }
    void onEvent(double, std::string_view e, std::string_view) override { gas_events += e.rfind("gas", 0) == 0; }
  } rec;
  Simulation sim(config::RobotConfig{}, World{}, 1, &rec);  // no `gas` section: no channels
  sim.advanceTo(500);
  std::vector<uint8_t> tx;
  sim.takeTx(tx);
  for (const auto& f : inspect::test::decodeSensorFrames(tx)) {
    EXPECT_EQ(f.gas_raw, (std::array<uint16_t, 4>{}));
    EXPECT_EQ(f.faults & serial::kFaultGasSensor, 0);
  }
  EXPECT_EQ(rec.gas_rows, 0);
  EXPECT_EQ(rec.gas_events, 0);
  // A world with leaks needs channels to sense them.
  try {
    Simulation bad(config::RobotConfig{}, loadWorldFile(inspect::test::srcPath("config/worlds/gas_lab.yaml")), 1);
    ADD_FAILURE() << "no error";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("gas.sources[0].gas: 'CH4' is not a gas channel of the robot (robot config "
                                         "gas.channels: none)"),
              std::string::npos)
        << e.what();
  }
}

TEST(GasSimulation, SameSeedSameReadings) {
  const World w = loadWorldFile(inspect::test::srcPath("config/worlds/gas_lab.yaml"));
  auto run = [&](uint64_t seed) {
    Simulation sim(gasRobot(), w, seed);
    sim.advanceTo(500);
    std::vector<uint8_t> tx;
    sim.takeTx(tx);
    std::vector<std::array<uint16_t, 4>> out;
    for (const auto& f : inspect::test::decodeSensorFrames(tx)) out.push_back(f.gas_raw);
    return out;
  };
  EXPECT_EQ(run(5), run(5));
  EXPECT_NE(run(5), run(6));
}

// --- world file ---

TEST(GasWorld, ErrorsNameFileKeyAndReason) {
  struct Case {
    std::string yaml;
    const char* key;
    const char* reason;
  };
  const std::string ok_src = "  sources: [{gas: CH4, x_m: 1, y_m: 1, rate: 5}]\n";
  const Case cases[] = {
      {room(3, "  diffusivity_m2_s: 0\n"), "gas.diffusivity_m2_s", "must be positive"},
      {room(3, "  diffusivity_m2_s: 20\n"), "gas.diffusivity_m2_s", "out of range"},
      {room(3, "  ventilation_per_s: -1\n"), "gas.ventilation_per_s", "out of range"},
      {room(3, "  airflow_m_s: [0.1]\n"), "gas.airflow_m_s", "exactly 2"},
      {room(3, "  airflow_m_s: [0.1, 9]\n"), "gas.airflow_m_s", "[-5, 5]"},
      {room(3, "  cell_m: 0.001\n"), "gas.cell_m", "out of range"},
      {room(3, "  diffusion: 0.1\n"), "gas.diffusion", "unknown key"},
      {room(3, "  sources: [{gas: CH4, x_m: 1, y_m: 1, rate: 5, colour: red}]\n"), "gas.sources[0].colour",
       "unknown key"},
      {room(3, "  sources: [{gas: CH4, x_m: 1, y_m: 1}]\n"), "gas.sources[0].rate", "missing"},
      {room(3, "  sources: [{gas: CH4, x_m: 1, y_m: 1, rate: 0}]\n"), "gas.sources[0].rate", "positive"},
      {room(3, "  sources: [{gas: 'CH 4', x_m: 1, y_m: 1, rate: 1}]\n"), "gas.sources[0].gas", "not a gas channel"},
      {room(3, "  sources: [{gas: CH4, x_m: 9, y_m: 1, rate: 5}]\n"), "gas.sources[0].x_m", "outside the walls"},
      {room(3, "  sources: [{gas: CH4, x_m: 0.5, y_m: 0.5, rate: 5}]\n",
            "obstacles:\n  - {name: tank, vertices_m: [0, 0, 1, 0, 1, 1, 0, 1]}\n"),
       "gas.sources[0].x_m", "inside obstacle 'tank'"},
      {room(3, "  sources: [{gas: CH4, x_m: 1, y_m: 3, rate: 5}]\n"), "gas.sources[0].x_m", "outside"},
      {room(3, "  sources: [{gas: CH4, x_m: 1, y_m: 1, rate: 5, start_s: 10, end_s: 5}]\n"), "gas.sources[0].end_s",
       "later than start_s"},
      {room(3, "  ventilation_per_s: 0\n  sources: [{gas: CH4, x_m: 1, y_m: 1, rate: 5, start_s: -3600}]\n"),
       "gas.sources[0].start_s", "never settles"},
      {room(3, ok_src + "  sources_extra: 1\n"), "gas.sources_extra", "unknown key"},
      {room(3, "  sources:\n    - {name: a, gas: CH4, x_m: 1, y_m: 1, rate: 5}\n"
               "    - {name: a, gas: H2S, x_m: 1, y_m: 2, rate: 5}\n"),
       "gas.sources[1].name", "already used"},
      {room(3, "  faults: [{channel: CO, kind: broken}]\n"), "gas.faults[0].kind", "broken"},
      {room(3, "  faults: [{channel: CO}]\n"), "gas.faults[0].kind", "required"},
      {room(3, "  faults: [{channel: CO, kind: stuck, start_s: -1}]\n"), "gas.faults[0].start_s", "out of range"},
      {"gas:\n  sources: [{gas: CH4, x_m: 1, y_m: 1, rate: 5}]\n", "gas.sources[0].x_m", "needs walls"},
  };
  for (const auto& c : cases) {
    const auto e = test::worldError(c.yaml, "gas_world.yaml");
    EXPECT_NE(e.find(std::string("gas_world.yaml: ") + c.key + ":"), std::string::npos) << c.yaml << " -> " << e;
    EXPECT_NE(e.find(c.reason), std::string::npos) << c.yaml << " -> " << e;
  }
  // A wall edge, in the middle of the room:
  const auto on_wall = test::worldError(
      room(3, "  sources: [{gas: CH4, x_m: 1, y_m: 0, rate: 5}]\n", "  - {from_m: [0, 0], to_m: [2, 0]}\n"),
      "gas_world.yaml");
  EXPECT_NE(on_wall.find("gas.sources[0].x_m: leak at (1, 0) lies on a wall"), std::string::npos) << on_wall;
}

TEST(GasWorld, GasNamesMustBeRobotChannels) {
  const auto e = simError(room(3, "  sources: [{gas: NH3, x_m: 1, y_m: 1, rate: 5}]\n"));
  EXPECT_NE(e.find("gas_world.yaml: gas.sources[0].gas: 'NH3' is not a gas channel of the robot"), std::string::npos)
      << e;
  EXPECT_NE(e.find("CH4, H2S, CO, O2"), std::string::npos) << e;
  const auto f = simError(room(3, "  faults: [{channel: C0, kind: dropout}]\n"));
  EXPECT_NE(f.find("gas_world.yaml: gas.faults[0].channel: 'C0' is not a gas channel"), std::string::npos) << f;
  const auto big =
      simError(room(3, "  cell_m: 0.02\n  diffusivity_m2_s: 10\n  sources: [{gas: CH4, x_m: 1, y_m: 1, rate: 5}]\n"));
  EXPECT_NE(big.find("gas_world.yaml: gas.cell_m:"), std::string::npos) << big;
  EXPECT_NE(big.find("cell updates per second"), std::string::npos) << big;
  EXPECT_EQ(simError(room(3, "  sources: [{gas: O2, x_m: 1, y_m: 1, rate: 5}]\n")), "");
}

TEST(GasWorld, DocsExampleLoadsAndRuns) {
  std::ifstream in(inspect::test::srcPath("docs/world-format.md"));
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string doc = ss.str();
  const auto example = doc.find("## Example");
  ASSERT_NE(example, std::string::npos);
  const auto begin = doc.find("```yaml\n", example) + 8;
  const auto end = doc.find("```", begin);
  const World w = loadWorldText(doc.substr(begin, end - begin), "example.yaml");
  ASSERT_EQ(w.gas.sources.size(), 1u);
  Simulation sim(gasRobot(), w, 1);
  sim.advanceTo(70000);
  EXPECT_GT(sim.trueConcentration(0, {17.5, 1.5}), 1.0);  // on since 60 s
}

// --- the shipped gas_lab world ---

TEST(GasLab, SteadyPlumesRaiseAndClearAlarmsAlongTheRoute) {
  const config::RobotConfig robot = config::loadRobotConfigFile(inspect::test::srcPath("config/robot.yaml"));
  const World w = loadWorldFile(inspect::test::srcPath("config/worlds/gas_lab.yaml"));
  const auto t0 = std::chrono::steady_clock::now();
  Simulation sim(robot, w, 1);
  const double build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const auto& gas = robot.gas;
  const int ch4 = gas.find("CH4"), h2s = gas.find("H2S"), o2 = gas.find("O2");
  ASSERT_GE(ch4, 0);
  ASSERT_GE(h2s, 0);
  ASSERT_GE(o2, 0);
  const Vec2 valve{6.0, 2.4}, drain{3.5, 3.6};
  std::printf("GAS gas_lab grid %d x %d cells of %.2f m, built (incl. steady state) in %.1f ms\n", sim.gas().nx(),
              sim.gas().ny(), sim.gas().cellM(), build_ms);
  std::printf("GAS gas_lab true values along the route (t = 0, steady):\n");
  std::printf("GAS    x  | y=1.5: CH4 %%LEL  H2S ppm  O2 %%vol | y=4.5: CH4 %%LEL  H2S ppm  O2 %%vol\n");
  for (double y : {1.5, 4.5}) {
    for (double x = 0.5; x <= 9.51; x += 0.5) {
      const Vec2 p{x, y};
      const double c = sim.trueConcentration(ch4, p), s = sim.trueConcentration(h2s, p),
                   o = sim.trueConcentration(o2, p);
      const double d_valve = std::hypot(x - valve.x, y - valve.y);
      const double d_drain = std::hypot(x - drain.x, y - drain.y);
      if (d_valve >= 3.0) {
        EXPECT_LT(c, gas.channels[ch4].alarm_low) << x << "," << y;
      }
      if (d_drain >= 3.0) {
        EXPECT_LT(s, gas.channels[h2s].alarm_low) << x << "," << y;
      }
      EXPECT_GT(o, gas.channels[o2].alarm_low) << x << "," << y;
    }
  }
  for (double x = 0.5; x <= 9.51; x += 0.5) {
    const Vec2 a{x, 1.5}, b{x, 4.5};
    std::printf("GAS  %4.1f  |       %6.2f    %6.2f   %6.3f  |       %6.2f    %6.2f   %6.3f\n", x,
                sim.trueConcentration(ch4, a), sim.trueConcentration(h2s, a), sim.trueConcentration(o2, a),
                sim.trueConcentration(ch4, b), sim.trueConcentration(h2s, b), sim.trueConcentration(o2, b));
  }
  // Passing each leak at 0.9 m: above A2.
  const double at_valve = sim.trueConcentration(ch4, {6.0, 1.5});
  const double at_drain = sim.trueConcentration(h2s, {3.5, 4.5});
  std::printf("GAS at 0.9 m: CH4 %.2f %%LEL (A2 %.0f), H2S %.2f ppm (A2 %.0f)\n", at_valve,
              gas.channels[ch4].alarm_high, at_drain, gas.channels[h2s].alarm_high);
  EXPECT_GE(at_valve, 25.0);
  EXPECT_LE(at_valve, 40.0);
  EXPECT_GE(at_drain, 12.0);
  EXPECT_LE(at_drain, 20.0);
  EXPECT_GT(at_valve, gas.channels[ch4].alarm_high);
  EXPECT_GT(at_drain, gas.channels[h2s].alarm_high);
  // The other aisle stays clear of the other leak (the bench is between).
  EXPECT_LT(sim.trueConcentration(ch4, {6.0, 4.5}), gas.channels[ch4].alarm_low);
  EXPECT_LT(sim.trueConcentration(h2s, {3.5, 1.5}), gas.channels[h2s].alarm_low);
  // Steady plumes (an hour old at t = 0): they stay as they are.
  sim.advanceTo(60000);
  EXPECT_TRUE(sim.gas().steady(0));
  EXPECT_TRUE(sim.gas().steady(1));
  EXPECT_EQ(sim.trueConcentration(ch4, {6.0, 1.5}), at_valve);
  EXPECT_EQ(sim.trueConcentration(h2s, {3.5, 4.5}), at_drain);
}

TEST(GasLab, DrivingTheSouthAisleTheCh4AlarmWouldRaiseAndClear) {
  // Straight along y = 1.5 at 0.4 m/s past valve_A, the sensors' lag included (CH4 t90 = 6 s).
  const config::RobotConfig robot = config::loadRobotConfigFile(inspect::test::srcPath("config/robot.yaml"));
  struct Rec : SimObserver {
    std::vector<std::array<double, 4>> rows;  // x of the inlet, true CH4, read CH4, read H2S
    void onGas(const GasSample& s) override {
      rows.push_back({s.inlet_x_m, s.true_value[0], s.reading[0], s.reading[1]});
    }
  } rec;
  Simulation sim(robot, loadWorldFile(inspect::test::srcPath("config/worlds/gas_lab.yaml")), 1, &rec);
  serial::FrameEncoder enc;
  while (sim.state().pose.x_m < 9.0 && sim.timeMs() < 40000) {
    sim.receive(enc.encode(serial::WheelCommand{2000, 2000, serial::WheelCommand::kEnable}).span());
    sim.advanceTo(sim.timeMs() + 10);
  }
  ASSERT_GE(sim.state().pose.x_m, 9.0);
  EXPECT_NEAR(sim.state().pose.y_m, 1.5, 0.05);
  const double at_9m = rec.rows.back()[2];
  sim.advanceTo(sim.timeMs() + 10000);  // the watchdog stops the robot; the sensor catches up
  const auto& ch4 = robot.gas.channels[0];
  double peak = 0.0, peak_x = 0.0, first_a2 = -1.0, last_a2 = -1.0;
  for (const auto& r : rec.rows) {
    if (r[2] > peak) peak = r[2], peak_x = r[0];
    if (r[2] >= ch4.alarm_high) {
      if (first_a2 < 0) first_a2 = r[0];
      last_a2 = r[0];
    }
  }
  std::printf("GAS drive at 0.4 m/s along y = 1.5: CH4 reading peaks at %.1f %%LEL at inlet x = %.2f m; >= A2 (%.0f) "
              "from x = %.2f to %.2f m; at x = 9 m %.1f %%LEL, 10 s later %.1f; H2S at most %.2f ppm\n",
              peak, peak_x, ch4.alarm_high, first_a2, last_a2, at_9m, rec.rows.back()[2],
              std::max_element(rec.rows.begin(), rec.rows.end(), [](auto& a, auto& b) { return a[3] < b[3]; })->at(3));
  EXPECT_GT(peak, ch4.alarm_high);
  EXPECT_GT(peak_x, 6.0);  // the lag puts the peak past the valve
  EXPECT_LT(rec.rows.back()[2], ch4.alarm_low - ch4.hysteresis);
  EXPECT_LT(rec.rows.front()[2], ch4.alarm_low);
}

TEST(GasLab, GasUpdateCost) {
  const World w = loadWorldFile(inspect::test::srcPath("config/worlds/gas_lab.yaml"));
  const auto tb = std::chrono::steady_clock::now();
  GasModel g(w);
  std::printf("GAS gas_lab: GasModel built (grid + steady states) in %.1f ms\n",
              std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tb).count());
  EXPECT_TRUE(g.steady(0));
  EXPECT_TRUE(g.steady(1));
  // The cost of stepping both fields: the same room with leaks that started 60 s ago (not yet steady).
  World young = w;
  for (auto& s : young.gas.sources) s.start_s = -60.0;
  const auto ty = std::chrono::steady_clock::now();
  GasModel moving(young);
  const double young_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - ty).count();
  EXPECT_FALSE(moving.steady(0));
  constexpr int n = 2000;  // 100 s of sim time
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 1; i <= n; ++i) moving.advanceTo(i * (Simulation::kGasPeriod_ms / 1000.0));
  const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() / n;
  std::printf("GAS gas_lab: one 50 ms update (%zu fields stepped, %d x %d cells, %lld sub-steps) takes %.1f us = %.2f %% "
              "of real time; pre-integrating 60 s took %.1f ms\n",
              moving.gases().size(), moving.nx(), moving.ny(), static_cast<long long>(moving.substeps(0.05)), us, us / 50000.0 * 100.0,
              young_ms);
  EXPECT_LT(us, 5000.0);  // even on a loaded machine: < 10 % of real time

  // The whole simulation in process, 20 s of sim time, with and without the gas.
  const auto speed = [](const config::RobotConfig& robot, const World& world) {
    Simulation sim(robot, world, 1);
    const auto t1 = std::chrono::steady_clock::now();
    sim.advanceTo(20000);
    return 20.0 / std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  };
  World no_gas = w;
  no_gas.gas = {};
  const double steady = speed(gasRobot(), w), stepped = speed(gasRobot(), young),
               without = speed(config::RobotConfig{}, no_gas);
  std::printf("GAS gas_lab: Simulation runs %.0f x real time with steady gas, %.0f x with the fields stepped, %.0f x "
              "without gas\n",
              steady, stepped, without);
}

TEST(GasLab, TruthLogHasGasRowsAndSourceEvents) {
  const std::string path =
      (std::filesystem::temp_directory_path() / ("gas_truth_" + std::to_string(::getpid()) + ".csv")).string();
  {
    TruthLog truth(path);
    Simulation sim(gasRobot(), loadWorldFile(inspect::test::srcPath("config/worlds/gas_lab.yaml")), 1, &truth);
    sim.advanceTo(1000);
  }
  std::ifstream in(path);
  std::string line;
  std::vector<std::vector<std::string>> g_rows;
  std::vector<std::string> sources;
  bool header = false;
  while (std::getline(in, line)) {
    header = header || line.rfind("# G,mono_ns,sim_t_s,inlet_x_m,inlet_y_m,true0,", 0) == 0;
    if (line.find(",gas_source,") != std::string::npos) sources.push_back(line);
    if (line.rfind("G,", 0) != 0) continue;
    std::vector<std::string> cols;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) cols.push_back(c);
    g_rows.push_back(cols);
  }
  std::filesystem::remove(path);
  EXPECT_TRUE(header);
  ASSERT_EQ(sources.size(), 2u);
  EXPECT_NE(sources[0].find("name=valve_A gas=CH4 x=6.000 y=2.400 rate=15"), std::string::npos) << sources[0];
  EXPECT_NE(sources[1].find("name=drain_B gas=H2S x=3.500 y=3.600 rate=7"), std::string::npos) << sources[1];
  ASSERT_EQ(g_rows.size(), 10u);  // 0.0 .. 0.9 s
  for (std::size_t i = 0; i < g_rows.size(); ++i) {
    const auto& r = g_rows[i];
    ASSERT_EQ(r.size(), 5u + 8u);
    EXPECT_NEAR(std::stod(r[2]), 0.1 * static_cast<double>(i), 1e-9);
    EXPECT_NEAR(std::stod(r[3]), 1.2 + 0.25, 1e-4);  // inlet 0.25 m ahead of the start pose
    EXPECT_NEAR(std::stod(r[4]), 1.5, 1e-4);
    EXPECT_NEAR(std::stod(r[8]), 20.9 - 0.0105 * std::stod(r[5]), 1e-3);  // true O2
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(std::stod(r[9 + c]), std::stod(r[5 + c]), 5.0) << i;
  }
}
