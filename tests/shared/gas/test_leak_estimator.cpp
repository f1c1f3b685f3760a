// Concentration maps and leak-source estimates on synthetic runs: an analytic
// plume (steady 2-D diffusion with removal, K0-shaped, lambda 1 m) read by a
// first-order sensor with noise at 50 Hz along straight passes at 0.4 m/s.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "shared/gas/concentration_map.hpp"
#include "shared/gas/leak_estimator.hpp"

using namespace inspect::gas;

namespace {

constexpr double kRate = 50.0;            // telemetry, Hz
constexpr double kSpeed = 0.4;            // m/s
const double kTauCh4 = 6.0 / std::log(10.0);  // t90 6 s (std::log is not constexpr in clang)

struct Plume {
  double x_m = 0.3, y_m = 0.9;  // source
  double lambda_m = 1.0;        // sqrt(D / k)
  double q = 23.75;             // 10 units above background at 1 m
  double background = 0.0;
  double sign = 1.0;            // -1: the gas displaces the channel's value (O2)
  double wind_m_s = 0.0;        // airflow along +x (D = 0.05 m^2/s, k = D / lambda^2)
  double at(double x, double y) const {
    const double r = std::max(std::hypot(x - x_m, y - y_m), 0.05);
    if (wind_m_s == 0.0) return background + sign * q * std::cyl_bessel_k(0.0, r / lambda_m);
    // Steady advection-diffusion with removal: exp(u dx / 2D) K0(r sqrt(u^2 / 4D^2 + k / D)).
    const double d = 0.05, k = d / (lambda_m * lambda_m), a = wind_m_s / (2 * d);
    return background + sign * q * std::exp(a * (x - x_m)) * std::cyl_bessel_k(0.0, r * std::sqrt(a * a + k / d));
  }
};

struct Leg {
  double x_m, y_m;   // go to here
  double dwell_s = 0;  // then wait this long
};

// Drives from `start` through `legs` at kSpeed, the sensor (lag tau_s, noise
// sd) sampled at kRate; the sensor starts settled at the start.
std::vector<GasSample> drive(const Plume& plume, double start_x, double start_y, const std::vector<Leg>& legs,
                             double tau_s, double noise_sd, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_sd);
  std::vector<GasSample> out;
  double x = start_x, y = start_y, t = 0, sensor = plume.at(x, y);
  const double dt = 1.0 / kRate;
  constexpr int kSub = 10;  // the sensor integrated finer than it is sampled
  auto step = [&](double vx, double vy) {
    for (int k = 0; k < kSub; ++k) {
      x += vx * dt / kSub, y += vy * dt / kSub;
      sensor += (plume.at(x, y) - sensor) * (1.0 - std::exp(-dt / kSub / tau_s));
    }
    t += dt;
    out.push_back({t, x, y, sensor + noise(rng)});
  };
  for (const auto& leg : legs) {
    const double d = std::hypot(leg.x_m - x, leg.y_m - y);
    const int n = static_cast<int>(std::round(d / kSpeed * kRate));
    const double vx = (leg.x_m - x) / (n * dt), vy = (leg.y_m - y) / (n * dt);
    for (int i = 0; i < n; ++i) step(vx, vy);
    for (int i = 0; i < static_cast<int>(leg.dwell_s * kRate); ++i) step(0, 0);
  }
  return out;
}

// The room: the robot drives along y = 0 with a wall 0.5 m to its right.
const Bounds kRoom{-7.0, -0.5, 7.0, 4.5};

double dist(const LeakEstimate& e, const Plume& p) { return std::hypot(e.x_m - p.x_m, e.y_m - p.y_m); }

void print(const char* what, const LeakEstimate& e, const Plume& p) {
  std::printf("%s: found %d, (%.2f, %.2f) best (%.2f, %.2f) error %.2f m, radius95 %.2f m, L %.2f, A %.3g, "
              "snr %.1f, LR %.0f, n_eff %.0f %s\n",
              what, e.found, e.x_m, e.y_m, e.best_x_m, e.best_y_m, dist(e, p), e.radius95_m, e.length_m,
              e.amplitude, e.snr, e.likelihood_ratio, e.n_eff, e.reason.c_str());
}

}  // namespace

TEST(LeakEstimator, StraightPassAt0p9m) {
  const Plume plume;  // (0.3, 0.9)
  const auto s = drive(plume, -6, 0, {{6, 0}}, kTauCh4, 0.3, 1);
  const auto e = estimateLeak(s, kTauCh4, 0.0, kRoom);
  print("0.9 m pass", e, plume);
  ASSERT_TRUE(e.found) << e.reason;
  EXPECT_LT(dist(e, plume), 0.5);
  EXPECT_LE(dist(e, plume), e.radius95_m);
  EXPECT_NEAR(e.background, 0.0, 0.3);
  EXPECT_NE(e.reason.find("one side"), std::string::npos) << e.reason;
}

TEST(LeakEstimator, StraightPassAt2m) {
  Plume plume;
  plume.y_m = 2.0;
  const auto s = drive(plume, -6, 0, {{6, 0}}, kTauCh4, 0.3, 2);
  const auto e = estimateLeak(s, kTauCh4, 0.0, kRoom);
  print("2 m pass", e, plume);
  ASSERT_TRUE(e.found) << e.reason;
  EXPECT_LT(dist(e, plume), 1.0);
  EXPECT_LE(dist(e, plume), e.radius95_m);
}

TEST(LeakEstimator, EstimatesHoldOverNoiseSeeds) {
  // The 95 % circle should hold the source in (nearly) every run.
  for (double lateral : {0.9, 2.0}) {
    Plume plume;
    plume.y_m = lateral;
    int covered = 0, runs = 0;
    double worst = 0.0;
    for (unsigned seed = 10; seed < 20; ++seed, ++runs) {
      const auto e = estimateLeak(drive(plume, -6, 0, {{6, 0}}, kTauCh4, 0.3, seed), kTauCh4, 0.0, kRoom);
      ASSERT_TRUE(e.found) << e.reason;
      worst = std::max(worst, dist(e, plume));
      covered += dist(e, plume) <= e.radius95_m;
    }
    std::printf("lateral %.1f m: worst error %.2f m, 95 %% circle covers %d of %d\n", lateral, worst, covered, runs);
    EXPECT_LT(worst, lateral < 1.0 ? 0.5 : 1.0);
    EXPECT_GE(covered, runs - 1);
  }
}

TEST(LeakEstimator, SinglePassCannotTellTheSideWithoutAWall) {
  // Nothing breaks the mirror symmetry of a straight pass: the 95 % circle
  // must then hold both sides; a wall along the path settles it.
  const Plume plume;
  const auto s = drive(plume, -6, 0, {{6, 0}}, kTauCh4, 0.3, 3);
  const Bounds open{-7.0, -4.5, 7.0, 4.5};
  const auto e = estimateLeak(s, kTauCh4, 0.0, open);
  print("open", e, plume);
  ASSERT_TRUE(e.found) << e.reason;
  EXPECT_LE(dist(e, plume), e.radius95_m);
  EXPECT_LE(std::hypot(e.x_m - plume.x_m, e.y_m + plume.y_m), e.radius95_m);  // the mirror image
  EXPECT_TRUE(e.split);
  EXPECT_NE(e.reason.find("fall apart"), std::string::npos) << e.reason;
  LeakOptions with_wall;
  with_wall.walls = {{-7.0, -0.5, 7.0, -0.5}};
  with_wall.surface_band_m = 0.0;  // the source stands in the open here
  const auto w = estimateLeak(s, kTauCh4, 0.0, open, with_wall);
  print("wall", w, plume);
  ASSERT_TRUE(w.found) << w.reason;
  EXPECT_LT(dist(w, plume), 0.5);
  EXPECT_LT(w.radius95_m, e.radius95_m);
  EXPECT_FALSE(w.split);
}

TEST(LeakEstimator, PassesOnBothSidesBeatOne) {
  const Plume plume;  // between y = 0 and y = 1.8
  const auto one = drive(plume, -6, 0, {{6, 0}}, kTauCh4, 0.3, 4);
  const auto two = drive(plume, -6, 0, {{6, 0}, {6, 1.8}, {-6, 1.8}}, kTauCh4, 0.3, 4);
  const auto e1 = estimateLeak(one, kTauCh4, 0.0, kRoom);
  const auto e2 = estimateLeak(two, kTauCh4, 0.0, kRoom);
  print("one pass", e1, plume);
  print("two passes", e2, plume);
  ASSERT_TRUE(e1.found && e2.found);
  EXPECT_LT(e2.radius95_m, e1.radius95_m);
  EXPECT_LT(std::sqrt(e2.cov_xx_m2 + e2.cov_yy_m2), std::sqrt(e1.cov_xx_m2 + e1.cov_yy_m2));
  EXPECT_LT(dist(e2, plume), 0.25);
  EXPECT_LE(dist(e2, plume), e2.radius95_m);
}

TEST(LeakEstimator, AirflowSkewedPlumeWithPassesOnBothSides) {
  // The model has no airflow; a weak draught (0.03 m/s) skews the plume downwind.
  Plume plume;
  plume.wind_m_s = 0.03;
  const auto s = drive(plume, -6, 0, {{6, 0}, {6, 1.8}, {-6, 1.8}}, kTauCh4, 0.3, 13);
  const auto e = estimateLeak(s, kTauCh4, 0.0, kRoom);
  print("airflow", e, plume);
  ASSERT_TRUE(e.found) << e.reason;
  EXPECT_LT(dist(e, plume), 0.5);
  EXPECT_LE(dist(e, plume), e.radius95_m);
  EXPECT_EQ(e.reason, "");  // seen from both sides, inside the searched area
}

TEST(LeakEstimator, PureNoiseFindsNothing) {
  Plume none;
  none.q = 0.0;
  none.background = 2.0;
  for (unsigned seed : {5u, 6u, 7u}) {
    const auto s = drive(none, -6, 0, {{6, 0}, {6, 1.8}, {-6, 1.8}}, kTauCh4, 0.3, seed);
    const auto e = estimateLeak(s, kTauCh4, 0.0, kRoom);
    EXPECT_FALSE(e.found) << "seed " << seed << " at (" << e.x_m << ", " << e.y_m << ")";
    EXPECT_FALSE(e.reason.empty());
    EXPECT_NEAR(e.noise_sd, 0.3, 0.05);
  }
}

TEST(LeakEstimator, TooFewSamplesOrNoMotion) {
  const Plume plume;
  auto s = drive(plume, -6, 0, {{6, 0}}, kTauCh4, 0.3, 8);
  s.resize(100);  // 2 s
  EXPECT_FALSE(estimateLeak(s, kTauCh4, 0.0, kRoom).found);
  const auto still = drive(plume, 0, 0, {{0, 0, 30.0}}, kTauCh4, 0.3, 8);
  const auto e = estimateLeak(still, kTauCh4, 0.0, kRoom);
  EXPECT_FALSE(e.found);
  EXPECT_NE(e.reason.find("path"), std::string::npos) << e.reason;
}

TEST(LeakEstimator, FallingChannelFitsTheDeficit) {
  // An inert gas displacing oxygen: O2 drops 1 %vol at 1 m from the source.
  Plume o2;
  o2.background = 20.9;
  o2.sign = -1.0;
  o2.q = 1.0 / std::cyl_bessel_k(0.0, 1.0);
  const double tau = 8.0 / std::log(10.0);
  const auto s = drive(o2, -6, 0, {{6, 0}}, tau, 0.03, 9);
  LeakOptions falling;
  falling.falling = true;
  const auto e = estimateLeak(s, tau, 20.9, kRoom, falling);
  print("O2", e, o2);
  ASSERT_TRUE(e.found) << e.reason;
  EXPECT_LT(dist(e, o2), 0.5);
  EXPECT_LE(dist(e, o2), e.radius95_m);
  EXPECT_NEAR(e.background, 20.9, 0.05);
  EXPECT_GT(e.amplitude, 0.0);
}

TEST(ConcentrationMap, LagCompensationPutsThePeakAtTheSource) {
  const Plume plume;
  const auto raw = drive(plume, -6, 0, {{6, 0}}, kTauCh4, 0.3, 11);
  const auto comp = compensateLag(raw, kTauCh4);
  const auto with = ConcentrationMap::build(comp, kRoom).peak();
  const auto without = ConcentrationMap::build(raw, kRoom).peak();
  ASSERT_TRUE(with.valid && without.valid);
  const double lag_m = kSpeed * kTauCh4;
  std::printf("map peak along the path: lag-compensated %+.2f m, raw %+.2f m from the source (v tau = %.2f m)\n",
              with.x_m - plume.x_m, without.x_m - plume.x_m, lag_m);
  EXPECT_LT(std::abs(with.x_m - plume.x_m), 0.7);
  // Without compensation the peak trails the source in the direction of travel by about v tau.
  EXPECT_GT(without.x_m - plume.x_m, 0.6 * lag_m);
  EXPECT_LT(without.x_m - plume.x_m, 1.4 * lag_m);
  // The path's cells have data, cells 2 m off it do not; the value there is NaN.
  const ConcentrationMap m = ConcentrationMap::build(comp, kRoom);
  const auto col = static_cast<std::size_t>((0.0 - kRoom.x_min_m) / m.cellM());
  const auto on = static_cast<std::size_t>((0.0 - kRoom.y_min_m) / m.cellM());
  const auto off = static_cast<std::size_t>((2.0 - kRoom.y_min_m) / m.cellM());
  EXPECT_TRUE(m.hasData(col, on));
  EXPECT_NEAR(m.coverage(col, on), 1.0, 1e-9);
  EXPECT_FALSE(m.hasData(col, off));
  EXPECT_TRUE(std::isnan(m.value(col, off)));
}

TEST(ConcentrationMap, CompensationRecoversAStep) {
  // A step through a first-order lag, undone: back at the step within the window.
  std::vector<GasSample> s;
  const double tau = 2.0;
  for (int i = 0; i < 1000; ++i) {
    const double t = i * 0.02;
    s.push_back({t, 0, 0, t < 5 ? 0.0 : 10.0 * (1 - std::exp(-(t - 5) / tau))});
  }
  const auto c = compensateLag(s, tau);
  for (const auto& x : c) {
    if (x.t_s < 4.4) {
      EXPECT_NEAR(x.value, 0.0, 1e-6) << x.t_s;
    }
    if (x.t_s > 5.6) {
      EXPECT_NEAR(x.value, 10.0, 0.2) << x.t_s;
    }
  }
  EXPECT_EQ(compensateLag(s, 0.0)[600].value, s[600].value);
}

TEST(ConcentrationMap, KernelInterpolatesAndPeaks) {
  // Two dwells 1 m apart: the map is a blend of them, nearer the nearer one;
  // the peak is the dwell cell (the path's), not a cell beyond it.
  std::vector<GasSample> s;
  for (int i = 0; i < 200; ++i) s.push_back({i * 0.02, 0.0, 0.0, 1.0});
  for (int i = 200; i < 400; ++i) s.push_back({i * 0.02, 1.0, 0.0, 3.0});
  const auto m = ConcentrationMap::build(s, {-1, -1, 2, 1});
  const auto p = m.peak();
  ASSERT_TRUE(p.valid);
  EXPECT_NEAR(p.x_m, 1.0, 0.1);
  EXPECT_NEAR(p.y_m, 0.0, 0.1);
  EXPECT_GT(p.value, 2.8);  // at the dwell: 3 blended with ~8 % of the other dwell's 1
  EXPECT_LT(p.value, 2.95);
  const auto lo = m.peak(true);
  EXPECT_NEAR(lo.x_m, 0.0, 0.1);
  EXPECT_LT(lo.value, 1.25);
  const auto [vmin, vmax] = m.valueRange();
  EXPECT_NEAR(vmin, 1.0, 1e-6);
  EXPECT_NEAR(vmax, 3.0, 1e-6);
  const auto mid = static_cast<std::size_t>((0.5 + 1.0) / m.cellM());
  const auto row = static_cast<std::size_t>(1.0 / m.cellM());
  EXPECT_NEAR(m.value(mid, row), 2.0, 0.15);
}

TEST(LeakEstimator, FiveMinuteRunTiming) {
  // 15000 samples: a lawn-mower pattern over a 10 m x 8 m room, lanes 0.8 m
  // apart, and a dwell at the end.
  Plume plume;
  plume.x_m = 2.3, plume.y_m = 3.4;
  std::vector<Leg> legs;
  for (int lane = 0; lane <= 10; ++lane) {
    const double x = lane % 2 ? -5.0 : 5.0, y = lane * 0.8;
    legs.push_back({x, y});
    if (lane < 10) legs.push_back({x, y + 0.8});
  }
  legs.back().dwell_s = 10.0;
  auto s = drive(plume, -5, 0, legs, kTauCh4, 0.3, 12);
  s.resize(std::min<std::size_t>(s.size(), 15000));
  ASSERT_EQ(s.size(), 15000u);
  const Bounds room{-6, -1, 6, 9};
  const auto t0 = std::chrono::steady_clock::now();
  const auto e = estimateLeak(s, kTauCh4, 0.0, room);
  const auto t1 = std::chrono::steady_clock::now();
  const auto m = ConcentrationMap::build(compensateLag(s, kTauCh4), room);
  const auto t2 = std::chrono::steady_clock::now();
  const auto ms = [](auto d) { return std::chrono::duration<double, std::milli>(d).count(); };
  std::printf("15000 samples: estimateLeak %.0f ms, compensateLag + map %.0f ms (%zu x %zu cells)\n", ms(t1 - t0),
              ms(t2 - t1), m.cols(), m.rows());
  print("lawn-mower", e, plume);
  ASSERT_TRUE(e.found) << e.reason;
  EXPECT_LT(dist(e, plume), 0.5);
}


// The gas_lab geometry: a bench north of the south aisle, the leak on its
// face, the route's V towards it; free-space plume (no reflection). Every
// combination of the surface band and wall images finds it; the defaults
// (band 0.6 m, no images) within 0.5 m.
TEST(LeakEstimator, LabBenchGeometry) {
  Plume plume;
  plume.x_m = 6.0;
  plume.y_m = 2.4;
  const auto s = drive(plume, 1.2, 1.5, {{3.5, 1.45}, {6.0, 1.85, 5.0}, {8.4, 1.45}, {8.6, 4.6}}, kTauCh4, 0.3, 5);
  const Bounds lab{-0.5, -0.5, 10.5, 6.5};
  LeakOptions o;
  o.walls = {{0, 0, 10, 0}, {10, 0, 10, 6}, {10, 6, 0, 6}, {0, 6, 0, 0},
             {2.5, 2.7, 7.5, 2.7}, {7.5, 2.7, 7.5, 3.3}, {7.5, 3.3, 2.5, 3.3}, {2.5, 3.3, 2.5, 2.7}};
  for (double band : {0.0, 0.6})
    for (bool refl : {false, true}) {
      o.surface_band_m = band;
      o.reflect_walls = refl;
      const auto e = estimateLeak(s, kTauCh4, 0.0, lab, o);
      std::printf("band %.1f reflect %d: ", band, refl);
      print("lab", e, plume);
      ASSERT_TRUE(e.found) << e.reason;
      EXPECT_LT(dist(e, plume), band > 0 && !refl ? 0.5 : 1.0) << band << " " << refl;
    }
}
