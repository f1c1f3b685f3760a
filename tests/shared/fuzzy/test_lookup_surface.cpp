// The lookup surface reproduces the engine at its nodes, interpolates
// between them within a stated error, and guards its inputs.
#include <array>
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "shared/fuzzy/engine.hpp"
#include "shared/fuzzy/fis_error.hpp"
#include "shared/fuzzy/fis_reader.hpp"
#include "shared/fuzzy/lookup_surface.hpp"
#include "tests/support/paths.hpp"

namespace inspect::fuzzy {
namespace {


Fis fuzzyPid() { return readFisFile(inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis")); }

TEST(LookupSurface, MatchesEngineAtGridNodes) {
  const Fis fis = fuzzyPid();
  const LookupSurface s(fis);
  Engine e(fis);
  ASSERT_EQ(s.pointsPerInput(), LookupSurface::kDefaultPoints2d);
  std::array<double, 3> direct{}, interp{};
  const double step = 6.0 / static_cast<double>(s.pointsPerInput() - 1);
  for (std::size_t i = 0; i < s.pointsPerInput(); i += 7) {
    for (std::size_t j = 0; j < s.pointsPerInput(); j += 5) {
      const std::array<double, 2> in{-3 + step * static_cast<double>(i), -3 + step * static_cast<double>(j)};
      e.evaluate(in, direct);
      ASSERT_EQ(s.evaluate(in, interp), EvalStatus::kOk);
      for (std::size_t o = 0; o < 3; ++o) EXPECT_NEAR(interp[o], direct[o], 1e-9);
    }
  }
}

TEST(LookupSurface, FuzzyPidDefaultResolutionErrorBound) {
  // Stated in docs/fuzzy.md: at the default 201 x 201 nodes the largest
  // difference from direct evaluation (on a 4x finer grid) is below 0.025 on
  // a [-3, 3] output (measured 0.0091 kpx, 0.0091 kix, 0.0222 kdx).
  const LookupSurface s(fuzzyPid());
  const auto per = s.maxInterpolationErrorPerOutput();
  ASSERT_EQ(per.size(), 3u);
  std::printf("fuzzy_pid lookup surface %zux%zu: max |error| kpx %.3g kix %.3g kdx %.3g\n", s.pointsPerInput(),
              s.pointsPerInput(), per[0], per[1], per[2]);
  for (double e : per) {
    EXPECT_GT(e, 0.0);  // the check does compare something off the nodes
    EXPECT_LT(e, 0.025);
  }
  EXPECT_DOUBLE_EQ(s.maxInterpolationError(), std::max({per[0], per[1], per[2]}));
}

TEST(LookupSurface, ErrorShrinksWithResolution) {
  const Fis fis = fuzzyPid();
  LookupOptions coarse;
  coarse.points_per_input = 21;
  LookupOptions fine;
  fine.points_per_input = 61;
  const double e_coarse = LookupSurface(fis, coarse).maxInterpolationError(2);
  const double e_fine = LookupSurface(fis, fine).maxInterpolationError(2);
  // min/max inference puts creases in the surface (where two rules or two
  // memberships swap), across which bilinear interpolation is first order.
  EXPECT_LT(e_fine, e_coarse / 2.0);
}

TEST(LookupSurface, OneAndThreeInputs) {
  // 1 input: the first input of fuzzy_pid alone; 3 inputs: a copy of it.
  Fis one = fuzzyPid();
  one.inputs.resize(1);
  for (auto& r : one.rules) r.antecedent.resize(1);
  const LookupSurface s1(one);
  EXPECT_EQ(s1.pointsPerInput(), LookupSurface::kDefaultPoints1d);
  EXPECT_LT(s1.maxInterpolationError(), 5e-3);

  Fis three = fuzzyPid();
  three.inputs.push_back(three.inputs[0]);
  three.inputs.back().name = "e2";
  for (auto& r : three.rules) r.antecedent.push_back(r.antecedent[0] == 4 ? 0 : 4);
  LookupOptions opt;
  opt.points_per_input = 25;
  const LookupSurface s3(three, opt);
  Engine e3(three);
  std::array<double, 3> direct{}, interp{};
  const std::array<double, 3> node{-3 + 0.25 * 5, -3 + 0.25 * 13, -3 + 0.25 * 20};
  e3.evaluate(node, direct);
  ASSERT_EQ(s3.evaluate(node, interp), EvalStatus::kOk);
  for (std::size_t o = 0; o < 3; ++o) EXPECT_NEAR(interp[o], direct[o], 1e-9);
  LookupOptions coarse;
  coarse.points_per_input = 13;
  EXPECT_LT(s3.maxInterpolationError(2), LookupSurface(three, coarse).maxInterpolationError(2));

  Fis four = three;
  four.inputs.push_back(four.inputs[0]);
  four.inputs.back().name = "e3";
  for (auto& r : four.rules) r.antecedent.push_back(0);
  EXPECT_THROW(LookupSurface{four}, FisError);
}

TEST(LookupSurface, ClampsOutOfRangeAndRejectsNonFinite) {
  const LookupSurface s(fuzzyPid());
  std::array<double, 3> a{}, b{};
  const std::array<double, 2> out_of_range{-10, 7}, edge{-3, 3};
  ASSERT_EQ(s.evaluate(out_of_range, a), EvalStatus::kOk);
  ASSERT_EQ(s.evaluate(edge, b), EvalStatus::kOk);
  for (std::size_t o = 0; o < 3; ++o) EXPECT_DOUBLE_EQ(a[o], b[o]);
  const std::array<double, 2> nan_in{std::nan(""), 0};
  EXPECT_EQ(s.evaluate(nan_in, a), EvalStatus::kNonFiniteInput);
  for (double v : a) EXPECT_TRUE(std::isnan(v));
  const std::array<double, 1> short_in{0};
  EXPECT_EQ(s.evaluate(short_in, a), EvalStatus::kBadSize);
}

}  // namespace
}  // namespace inspect::fuzzy
