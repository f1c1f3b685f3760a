// The camera's people in the people tracker (shared/behavior/camera_fusion.cpp):
// camera-only tracks, crossing motion observed through bearings, echoes the
// camera looks at and never confirms, occlusion, bearing-only updates, config.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "shared/behavior/human_awareness.hpp"
#include "shared/behavior/human_tracker.hpp"
#include "shared/config/config_node.hpp"
#include "tests/shared/behavior/sonar_echoes.hpp"

using namespace inspect;
using behavior::CameraLook;
using behavior::HumanTracker;
using test::Circle;
using test::echoes;

namespace {
constexpr double kDeg = M_PI / 180.0;

/// What a detector would report of `people` from the robot at `pose`: each
/// person inside the 60-degree view at 3-9 m, bearing noise 0.2 deg, the
/// foot-row range 15 % long +- 10 % (bench_people's HOG figures), unless
/// `feet` is false (bearing only).
CameraLook look(const control::Pose2& pose, const std::vector<Circle>& people, std::mt19937& rng, bool feet = true) {
  CameraLook l;
  std::normal_distribution<double> bearing_noise(0.0, 0.2 * kDeg), range_noise(1.15, 0.10);
  const double c = std::cos(pose.theta_rad), s = std::sin(pose.theta_rad);
  const double lx = pose.x_m + c * l.lens_x_m - s * l.lens_y_m, ly = pose.y_m + s * l.lens_x_m + c * l.lens_y_m;
  for (const auto& p : people) {
    const double d = std::hypot(p.x - lx, p.y - ly);
    const double b = std::remainder(std::atan2(p.y - ly, p.x - lx) - pose.theta_rad, 2 * M_PI);
    if (d < 3.0 || d > 9.0 || std::abs(b) > l.half_fov_rad) continue;
    l.add({b + bearing_noise(rng), feet ? d * range_noise(rng) : -1.0});
  }
  return l;
}

const behavior::HumanTrack* only(const HumanTracker& tr) {
  return tr.tracks().size() == 1 ? &tr.tracks()[0] : nullptr;
}
}  // namespace

TEST(CameraFusion, ACrossingPersonBeyondTheSonarsIsTrackedByTheCameraWithItsVelocity) {
  const config::UltrasonicConfig u;
  HumanTracker tr(u, {});
  std::mt19937 rng(1);
  const control::Pose2 robot{0, 0, 0};
  // 6 m ahead (beyond the sonars' 4.5 m), walking right at 1 m/s; 5 pictures a second.
  for (int k = 0; k <= 250; ++k) {
    const double t = k * 0.01;
    const Circle p{6.0, 1.5 - 1.0 * t, 0.25};
    tr.step(robot, echoes(u, robot, {p}, {}, &rng), t);
    if (k % 20 == 0) tr.observeCamera(robot, look(robot, {p}, rng));
  }
  const auto* n = only(tr);
  ASSERT_NE(n, nullptr) << tr.tracks().size() << " tracks";
  EXPECT_TRUE(n->isPerson());
  EXPECT_NEAR(n->x[3], -1.0, 0.2) << "crossing speed";
  EXPECT_NEAR(n->x[1], 1.5 - 2.5, 0.15) << "lateral position from the bearing";
  EXPECT_NEAR(n->x[0], 6.0 * 1.15, 1.0) << "range: as coarse as the foot row";
  EXPECT_EQ(tr.counters().camera_tracks_created, 1u);
  EXPECT_GE(tr.counters().camera_associated, 10u);
  EXPECT_EQ(tr.counters().echoes, 0u) << "no echo from 6 m";
}

TEST(CameraFusion, APersonTheCameraFoundFarOffKeepsOneTrackWhenTheSonarsHearThem) {
  // Walking straight at the robot from 6.5 m at 0.5 m/s; the foot row reads
  // 35 % long (the bench's p90 is +41 %), so the camera's track is about 1 m
  // beyond the person when the front sonars first hear them at 4.2 m, and
  // the two front ranges put them up to 0.9 m to a side: their echoes must go
  // to that track (range only), not start a second person.
  const config::UltrasonicConfig u;
  HumanTracker tr(u, {});
  std::mt19937 rng(4);
  const control::Pose2 robot{0, 0, 0};
  for (int k = 0; k <= 600; ++k) {
    const double t = k * 0.01;
    const Circle p{6.5 - 0.5 * t, 0.0, 0.25};
    tr.step(robot, echoes(u, robot, {p}, {}, &rng), t);
    if (k % 20 == 0) {
      CameraLook l;
      const double d = std::hypot(p.x - l.lens_x_m, p.y - l.lens_y_m);
      l.add({std::atan2(p.y - l.lens_y_m, p.x - l.lens_x_m), d * 1.35});
      tr.observeCamera(robot, l);
    }
  }
  const auto* n = only(tr);
  ASSERT_NE(n, nullptr) << tr.tracks().size() << " tracks: the sonars started a second person";
  EXPECT_EQ(tr.counters().tracks_created, 0u) << "no sonar track (merged into the camera's: "
                                               << tr.counters().camera_merged << ")";
  EXPECT_GE(tr.counters().camera_echo_joins, 1u);
  EXPECT_GT(tr.counters().associated, 100u) << "the echoes went to the camera's track";
  EXPECT_NEAR(n->x[0], 6.5 - 0.5 * 6.0, 0.4) << "the echoes fixed the range";
  EXPECT_TRUE(n->isPerson());
}

TEST(CameraFusion, TheFootRowsKnownBiasIsDividedOut) {
  const config::UltrasonicConfig u;
  behavior::HumanTrackerParams params;
  HumanTracker tr(u, params);
  tr.step({0, 0, 0}, {-1, -1, -1, -1}, 0.0);  // the tracker's time starts with a step
  CameraLook l;
  l.add({0.0, 7.0 * (1.0 + params.camera.range_bias_frac)});
  tr.observeCamera({0, 0, 0}, l);
  ASSERT_EQ(tr.tracks().size(), 1u);
  EXPECT_NEAR(tr.tracks()[0].x[0], l.lens_x_m + 7.0, 1e-6);
}

TEST(CameraFusion, TheCameraTellsCrossingFromRadialMotionWhereTheSonarsCannot) {
  // A person 3.5 m ahead crossing right to left at 0.8 m/s through both
  // front cones: the sonars see the range change little and the lateral
  // speed weakly; bearings at 5 Hz fix it.
  const config::UltrasonicConfig u;
  HumanTracker sonar_only(u, {}), fused(u, {});
  std::mt19937 rng_a(2), rng_b(2), rng_c(3);
  const control::Pose2 robot{0, 0, 0};
  double err_sonar = 0, err_fused = 0;
  int samples = 0;
  for (int k = 0; k <= 200; ++k) {
    const double t = k * 0.01;
    const Circle p{3.5, -0.8 + 0.8 * t, 0.25};
    sonar_only.step(robot, echoes(u, robot, {p}, {}, &rng_a), t);
    fused.step(robot, echoes(u, robot, {p}, {}, &rng_b), t);
    if (k % 20 == 0) fused.observeCamera(robot, look(robot, {p}, rng_c));
    if (k >= 120 && k % 10 == 0) {  // the last 0.8 s, the person inside the cones
      const auto* a = sonar_only.nearest(robot);
      const auto* b = fused.nearest(robot);
      ASSERT_NE(a, nullptr) << "t " << t;
      ASSERT_NE(b, nullptr) << "t " << t;
      err_sonar += std::hypot(a->x[2], a->x[3] - 0.8);
      err_fused += std::hypot(b->x[2], b->x[3] - 0.8);
      ++samples;
    }
  }
  err_sonar /= samples;
  err_fused /= samples;
  // Measured: 0.08 m/s with the camera, 0.56 sonar only.
  EXPECT_LT(err_fused, 0.2) << "velocity error with the camera, m/s";
  EXPECT_LT(err_fused, 0.5 * err_sonar) << "sonar only: " << err_sonar << " m/s";
  EXPECT_EQ(fused.tracks().size(), 1u) << "the sonars' own track of this person went into the camera's";
}

TEST(CameraFusion, AMovingEchoTheCameraLooksAtAndNeverFindsIsNotAPerson) {
  // Something that moves toward the robot from 4.2 m (a cart, a door): the
  // sonars make it a person; the camera, looking at it, finds nobody.
  const config::UltrasonicConfig u;
  HumanTracker sonar_only(u, {}), fused(u, {});
  std::mt19937 rng_a(4), rng_b(4);
  const control::Pose2 robot{0, 0, 0};
  bool sonar_person = false, fused_person_late = false;
  for (int k = 0; k <= 250; ++k) {
    const double t = k * 0.01;
    const Circle cart{4.3 - 0.4 * t, 0.0, 0.3};
    sonar_only.step(robot, echoes(u, robot, {cart}, {}, &rng_a), t);
    fused.step(robot, echoes(u, robot, {cart}, {}, &rng_b), t);
    if (k % 20 == 0) fused.observeCamera(robot, CameraLook{});  // looking ahead, nobody found
    if (k == 250) {
      sonar_person = sonar_only.nearest(robot) != nullptr;
      fused_person_late = fused.nearest(robot) != nullptr;
    }
  }
  EXPECT_TRUE(sonar_person) << "the sonars alone take it for a person";
  EXPECT_FALSE(fused_person_late) << "the camera says it is not";
  EXPECT_GE(fused.counters().camera_denials, 1u);
  EXPECT_GE(fused.counters().camera_misses, 6u);
  ASSERT_FALSE(fused.tracks().empty()) << "still tracked (its echoes go somewhere), not a person";
  EXPECT_TRUE(fused.tracks()[0].camera_denied);
}

TEST(CameraFusion, TheWideHeadDeniesAnEchoAtTwoMetresWhereThePtzHeadSaysNothing) {
  // The cart of the test above, from 2.4 m, 20 degrees off the axis: inside
  // the PTZ head's view but nearer than its detector finds anyone (recall 0
  // to 3 m): its pictures change nothing. The wide head (recall 0.57-0.70 at
  // 1.5-3 m) looking and not finding it is evidence against a person.
  const config::UltrasonicConfig u;
  HumanTracker ptz(u, {}), wide(u, {});
  std::mt19937 rng_a(4), rng_b(4);
  const control::Pose2 robot{0, 0, 0};
  CameraLook wide_look;
  wide_look.lens_x_m = 0.24;
  wide_look.half_fov_rad = 60.0 * kDeg;
  wide_look.wide = true;
  for (int k = 0; k <= 200; ++k) {
    const double t = k * 0.01;
    const double r = 2.4 - 0.4 * t;
    const Circle cart{r * std::cos(20 * kDeg), r * std::sin(20 * kDeg), 0.3};
    ptz.step(robot, echoes(u, robot, {cart}, {}, &rng_a), t);
    wide.step(robot, echoes(u, robot, {cart}, {}, &rng_b), t);
    if (k % 25 == 0) {
      ptz.observeCamera(robot, CameraLook{});
      wide.observeCamera(robot, wide_look);
    }
  }
  EXPECT_EQ(ptz.counters().camera_misses, 0u) << "the PTZ head neither sees it nor could find it there";
  EXPECT_GE(wide.counters().camera_misses, 4u);
  EXPECT_GE(wide.counters().camera_denials, 1u);
  EXPECT_NE(ptz.nearest(robot), nullptr) << "with the PTZ head's pictures alone the sonars make it a person";
  EXPECT_EQ(wide.nearest(robot), nullptr) << "the wide head looked and found nobody";
  ASSERT_FALSE(wide.tracks().empty()) << "still tracked, not a person";
  EXPECT_TRUE(wide.tracks()[0].camera_denied);
}

TEST(CameraFusion, AStandingPersonTheCameraFindsIsAPersonAndOneHiddenBehindIsNotCountedMissed) {
  const config::UltrasonicConfig u;
  HumanTracker tr(u, {});
  std::mt19937 rng(5);
  const control::Pose2 robot{0, 0, 0};
  const Circle front{4.8, 0.0, 0.25}, behind{7.0, 0.1, 0.25};
  for (int k = 0; k <= 200; ++k) {  // (hidden, the far one coasts: it goes 1.5 s after its last detection)
    const double t = k * 0.01;
    tr.step(robot, echoes(u, robot, {}, {}, &rng), t);
    if (k % 20 != 0) continue;
    // First both are found; from 1 s on the one behind is hidden by the one in front.
    tr.observeCamera(robot, k < 100 ? look(robot, {front, behind}, rng) : look(robot, {front}, rng));
  }
  ASSERT_EQ(tr.tracks().size(), 2u);
  for (const auto& t : tr.tracks()) {
    EXPECT_TRUE(t.isPerson()) << "standing still, found by the camera: track " << t.id;
    EXPECT_LT(t.speed(), 0.3);
  }
  const auto& far = tr.tracks()[0].x[0] > tr.tracks()[1].x[0] ? tr.tracks()[0] : tr.tracks()[1];
  EXPECT_EQ(far.camera_misses, 0) << "hidden: not evidence against it";
  EXPECT_EQ(tr.counters().camera_misses, 0u);
}

TEST(CameraFusion, ABearingWithoutARangeMovesTheTrackSideways) {
  const config::UltrasonicConfig u;
  HumanTracker tr(u, {});
  std::mt19937 rng(6);
  const control::Pose2 robot{0, 0, 0};
  // A standing person 5 m ahead; after 1 s only the bearing (feet hidden),
  // while the person steps 0.5 m to the left.
  for (int k = 0; k <= 200; ++k) {
    const double t = k * 0.01;
    tr.step(robot, echoes(u, robot, {}, {}, &rng), t);
    if (k % 20 != 0) continue;
    const Circle p{5.0, k < 100 ? 0.0 : 0.5 * (t - 1.0), 0.25};
    tr.observeCamera(robot, look(robot, {p}, rng, k < 100));
  }
  const auto* n = only(tr);
  ASSERT_NE(n, nullptr) << tr.tracks().size() << " tracks, " << tr.counters().camera_associated << " detections associated";
  EXPECT_NEAR(std::atan2(n->x[1], n->x[0] - 0.2), std::atan2(0.5, 4.8), 1.0 * kDeg) << "on the new bearing";
  EXPECT_GE(tr.counters().camera_associated, 9u);
  EXPECT_EQ(tr.counters().camera_tracks_created, 1u) << "bearings alone start no track";
}

TEST(CameraFusion, BadDetectionsAndAFullTableAreHarmless) {
  const config::UltrasonicConfig u;
  behavior::HumanTrackerParams p;
  p.max_tracks = 3;
  HumanTracker tr(u, p);
  const control::Pose2 robot{0, 0, 0};
  CameraLook l;
  l.add({std::nan(""), 5.0});
  l.add({0.1, std::numeric_limits<double>::infinity()});
  for (int i = 0; i < 6; ++i) l.add({-0.4 + 0.15 * i, 4.0 + i});
  EXPECT_FALSE(l.add({0.0, 5.0})) << "8 people a picture at most";
  tr.step(robot, {-1, -1, -1, -1}, 0.0);
  tr.observeCamera(robot, l);
  EXPECT_EQ(tr.tracks().size(), 3u);
  for (const auto& t : tr.tracks()) EXPECT_TRUE(t.x.allFinite());
  EXPECT_EQ(tr.counters().camera_detections, 6u) << "the two non-finite ones are not detections";
}

TEST(CameraFusion, AnEchoTheCameraMissedIsNotAPersonUntilTheCameraFindsIt) {
  // The cart of the test above, 4.5 m ahead: a picture without it (recall
  // 0.55 there: -0.8, below doubt_logodds) keeps it from becoming a person
  // while its evidence is still above the deny level; a detection ends the
  // doubt. The sonars alone make it a person within a second.
  const config::UltrasonicConfig u;
  HumanTracker sonar_only(u, {}), fused(u, {});
  std::mt19937 rng_a(4), rng_b(4), rng_c(5);
  const control::Pose2 robot{0, 0, 0};
  bool sonar_person = false, fused_person = true, fused_person_found = false;
  for (int k = 0; k <= 150; ++k) {
    const double t = k * 0.01;
    const Circle cart{4.5 - 0.4 * t, 0.0, 0.3};
    sonar_only.step(robot, echoes(u, robot, {cart}, {}, &rng_a), t);
    fused.step(robot, echoes(u, robot, {cart}, {}, &rng_b), t);
    if (k == 10 || k == 90) fused.observeCamera(robot, CameraLook{});  // looking ahead, nobody found
    if (k == 100) {
      sonar_person = sonar_only.nearest(robot) != nullptr;
      fused_person = fused.nearest(robot) != nullptr;
      ASSERT_FALSE(fused.tracks().empty());
      int doubted_people = 0;
      for (const auto& tr : fused.tracks()) {
        EXPECT_FALSE(tr.camera_denied) << "two misses are doubt, not denial";
        if (tr.person && tr.camera_doubted) ++doubted_people;
      }
      EXPECT_GE(doubted_people, 1) << "the sonars' rule holds, the camera's doubt overrides it";
      fused.observeCamera(robot, look(robot, {cart}, rng_c));
    }
    if (k == 150) fused_person_found = fused.nearest(robot) != nullptr;
  }
  EXPECT_TRUE(sonar_person);
  EXPECT_FALSE(fused_person) << "pictures without it: not a person yet";
  EXPECT_TRUE(fused_person_found) << "the camera found it: a person";
}

TEST(CameraFusion, ConfigReadsTheRecallTableAndNamesWhatIsWrong) {
  const auto load = [](const std::string& camera) {
    const auto root = config::ConfigNode::loadString("tracker:\n  camera: " + camera + "\n", "b.yaml");
    auto c = behavior::loadAwarenessConfig(root, ".");
    root.checkKnown();
    return c;
  };
  const auto c = load("{recall_upto_m: [2, 4, 6, 8, 12], recall: [0.1, 0.4, 0.6, 0.7, 0.5], hit_logodds: 3}");
  EXPECT_DOUBLE_EQ(c.tracker.camera.recallAt(5.0), 0.6);
  EXPECT_DOUBLE_EQ(c.tracker.camera.recallAt(13.0), 0.0);
  EXPECT_DOUBLE_EQ(c.tracker.camera.hit_logodds, 3.0);
  const auto fails = [&](const std::string& camera, const std::string& what) {
    try {
      load(camera);
      ADD_FAILURE() << camera << " was accepted";
    } catch (const config::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  fails("{recall_upto_m: [2, 4, 6, 8, 12], recall: [0.1, 0.4]}", "recall");
  fails("{recall_upto_m: [2, 4, 3, 8, 12], recall: [0.1, 0.4, 0.6, 0.7, 0.5]}", "recall_upto_m");
  fails("{recall_upto_m: [2, 4, 6, 8, 12], recall: [0.1, 1.4, 0.6, 0.7, 0.5]}", "recall");
  const auto w = load("{wide_recall_upto_m: [0.5, 1, 2, 3, 4], wide_recall: [0, 0.3, 0.7, 0.6, 0.1]}");
  EXPECT_DOUBLE_EQ(w.tracker.camera.recallAt(1.5, true), 0.7);
  EXPECT_DOUBLE_EQ(w.tracker.camera.recallAt(1.5, false), 0.0) << "the PTZ head's table is its own";
  EXPECT_DOUBLE_EQ(w.tracker.camera.recallAt(4.5, true), 0.0);
  fails("{wide_recall_upto_m: [0.5, 1, 2, 3, 4]}", "wide_recall");
  fails("{wide_recall_upto_m: [0.5, 1, 2, 3, 4], wide_recall: [0, 0.3, 0.7, -0.6, 0.1]}", "wide_recall");
  fails("{deny_logodds: 0, person_logodds: 0}", "deny_logodds");
  fails("{deny_logodds: -2, doubt_logodds: -3}", "doubt_logodds");
  fails("{bearing_sigma: 1}", "bearing_sigma");
}
