// The arena's camera people detector model (sim/detector_model): recall by
// distance and share visible, walls and people hiding people, the foot-row
// range error, false boxes - each against the figures it was calibrated on.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "sim/detector_model.hpp"
#include "tests/sim/world_text.hpp"

using namespace inspect;
using sim::DetectorModelParams;
using sim::PersonDisc;

namespace {
constexpr int kPictures = 4000;
const control::Pose2 kRobot{0, 0, 0};

struct Seen {
  double found = 0;  // share of pictures with a detection near the person
  std::vector<double> range_err, bearing_err_deg;
  double falses = 0;  // detections far from everyone, per picture
};

Seen watch(const world::World& w, const std::vector<PersonDisc>& people, std::size_t who, DetectorModelParams p = {}) {
  std::mt19937_64 rng(11);
  config::CameraMount mount;
  Seen s;
  const double lx = mount.x_m, ly = mount.y_m;
  const PersonDisc& target = people[who];
  const double d = std::hypot(target.x_m - lx, target.y_m - ly), b = std::atan2(target.y_m - ly, target.x_m - lx);
  for (int k = 0; k < kPictures; ++k) {
    const auto look = sim::detectPeople(w, kRobot, mount, 0.0, people, p, rng);
    bool hit = false;
    for (std::size_t i = 0; i < look.count; ++i) {
      const auto& q = look.people[i];
      bool near_someone = false;
      for (const auto& o : people)
        near_someone = near_someone || std::abs(q.bearing_rad - std::atan2(o.y_m - ly, o.x_m - lx)) < 0.02;
      if (!near_someone) {
        s.falses += 1;
        continue;
      }
      if (std::abs(q.bearing_rad - b) < 0.02) {
        hit = true;
        s.bearing_err_deg.push_back(std::abs(q.bearing_rad - b) * 180 / M_PI);
        if (q.range_m > 0) s.range_err.push_back((q.range_m - d) / d);
      }
    }
    if (hit) s.found += 1;
  }
  s.found /= kPictures;
  s.falses /= kPictures;
  return s;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? NAN : v[v.size() / 2];
}
}  // namespace

TEST(DetectorModel, RecallByDistanceForAClearViewIsTheBenchs) {
  const world::World open;
  DetectorModelParams p;
  p.false_per_picture = 0;
  // 5 m: the 4-6 m bin (0.73); 3.5 m: 3-4 m (0.44); 2.5 m: 2-3 m (0.06); 9 m: 0.62.
  EXPECT_NEAR(watch(open, {{5.2, 0.3, 0.25}}, 0, p).found, 0.73, 0.03);
  EXPECT_NEAR(watch(open, {{3.7, 0.0, 0.25}}, 0, p).found, 0.44, 0.03);
  EXPECT_NEAR(watch(open, {{2.7, 0.0, 0.25}}, 0, p).found, 0.06, 0.02);
  EXPECT_NEAR(watch(open, {{9.2, -1.0, 0.25}}, 0, p).found, 0.62, 0.03);
  EXPECT_EQ(watch(open, {{0.2, 6.0, 0.25}}, 0, p).found, 0.0) << "beside the robot: out of the picture";
}

TEST(DetectorModel, WallsAndPeopleInFrontHide) {
  const auto wall = test::worldOf("walls:\n  - {from_m: [3, -1], to_m: [3, 1]}\n");
  DetectorModelParams p;
  p.false_per_picture = 0;
  EXPECT_EQ(watch(wall, {{5.2, 0.0, 0.25}}, 0, p).found, 0.0) << "behind a wall";
  const world::World open;
  // Half hidden by a person 1.5 m closer and 0.3 m to the side: the 30-90 % recall (0.06 at 4-6 m).
  const std::vector<PersonDisc> two{{5.2, 0.0, 0.25}, {3.7, 0.3, 0.25}};
  const double share = sim::visibleShare(open, {0.2, 0, 0}, M_PI / 6, two[0], two);
  EXPECT_GT(share, 0.3);
  EXPECT_LT(share, 0.9);
  EXPECT_NEAR(watch(open, two, 0, p).found, 0.06, 0.02);
  EXPECT_NEAR(sim::visibleShare(open, {0.2, 0, 0}, M_PI / 6, two[1], two), 1.0, 1e-9) << "the one in front";
}

TEST(DetectorModel, RangeAndBearingErrorsAreTheBenchs) {
  const world::World open;
  const Seen s = watch(open, {{6.2, 0.5, 0.25}}, 0);
  ASSERT_GT(s.range_err.size(), 1000u);
  // bench_people, 640x480 hog with the floor band (2026-12-07).
  EXPECT_NEAR(median(s.range_err), 0.106, 0.02) << "the foot row reads long";
  std::vector<double> r = s.range_err;
  std::sort(r.begin(), r.end());
  EXPECT_NEAR(r[r.size() / 10], -0.068, 0.03) << "p10";
  EXPECT_NEAR(r[r.size() * 9 / 10], 0.355, 0.04) << "p90";
  EXPECT_NEAR(median(s.bearing_err_deg), 0.13, 0.03);
  EXPECT_NEAR(s.falses, 0.0033, 0.003) << "false boxes per picture";
}
