// Active looking (shared/behavior/active_look): the PTZ head turns to an
// undecided sonar track beside the robot where its detector reaches, holds
// there for the dwell, turns back, and leaves alone what it should.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "shared/behavior/active_look.hpp"

using namespace inspect;
using namespace inspect::behavior;

namespace {

constexpr double kLensX = 0.2, kHalfFov = 30 * std::numbers::pi / 180;
const RecallTable kRecall{{3.0, 4.0, 6.0, 8.0, 10.0}, {0.0, 0.34, 0.55, 0.65, 0.45}};

HumanTrack track(int id, double x, double y, bool person = false) {
  HumanTrack t;
  t.id = id;
  t.x << x, y, 0, 0;
  t.confirmed = true;
  t.person = person;
  return t;
}

double pan(ActiveLookState& st, const std::vector<HumanTrack>& tracks, double t, const ActiveLookParams& p = {}) {
  return activeLookPan(st, p, tracks, control::Pose2{}, kLensX, 0.0, kHalfFov, kRecall, t);
}

}  // namespace

TEST(ActiveLook, TurnsToAnUndecidedTrackBesideHoldsForTheDwellAndTurnsBack) {
  ActiveLookParams p;
  ActiveLookState st;
  const std::vector<HumanTrack> tracks{track(7, kLensX, 3.5)};  // 90 degrees left, 3.5 m: recall 0.34
  const double a = pan(st, tracks, 0.0, p);
  EXPECT_NEAR(a, std::numbers::pi / 2, 1e-9);
  EXPECT_EQ(st.target_id, 7);
  EXPECT_EQ(st.looks, 1);
  const double turn_s = (std::numbers::pi / 2) / (p.slew_deg_s * std::numbers::pi / 180);  // 0.5 s
  EXPECT_TRUE(activeLookTurning(st, 0.25));
  EXPECT_FALSE(activeLookTurning(st, turn_s + 0.01));
  EXPECT_NEAR(pan(st, tracks, turn_s + 0.5, p), std::numbers::pi / 2, 1e-9) << "held on the track";
  // The dwell over: back ahead, turning again; not looked at again within revisit_s.
  EXPECT_EQ(pan(st, tracks, turn_s + p.dwell_s + 0.01, p), 0.0);
  EXPECT_EQ(st.target_id, -1);
  EXPECT_TRUE(activeLookTurning(st, turn_s + p.dwell_s + 0.1));
  EXPECT_EQ(pan(st, tracks, 3.0, p), 0.0);
  EXPECT_EQ(st.looks, 1);
  // Off the path from the look's start to its end (the pan beyond 30 degrees), sampled where it was called.
  EXPECT_NEAR(st.off_path_s, turn_s + p.dwell_s + 0.01, 1e-9);
  // After revisit_s it may be looked at again.
  EXPECT_NEAR(pan(st, tracks, 0.0 + p.revisit_s + 0.1, p), std::numbers::pi / 2, 1e-9);
  EXPECT_EQ(st.looks, 2);
}

TEST(ActiveLook, EndsAtOnceWhenTheTrackIsSettledOrSomeoneIsAhead) {
  ActiveLookState st;
  std::vector<HumanTrack> tracks{track(7, kLensX, -3.5)};  // right
  EXPECT_NEAR(pan(st, tracks, 0.0), -std::numbers::pi / 2, 1e-9);
  tracks[0].camera_doubted = true;  // the look found nobody: settled
  EXPECT_EQ(pan(st, tracks, 0.8), 0.0);
  ActiveLookState st2;
  std::vector<HumanTrack> two{track(8, kLensX, 3.5)};
  EXPECT_GT(pan(st2, two, 0.0), 1.0);
  two.push_back(track(9, 3.0, 0.1, true));  // a person 2.8 m ahead
  EXPECT_EQ(pan(st2, two, 0.6), 0.0);
  EXPECT_EQ(pan(st2, two, 2.0), 0.0) << "no new look while someone is ahead";
}

TEST(ActiveLook, LeavesAloneWhatItShould) {
  const auto none = [](const std::vector<HumanTrack>& tracks, const ActiveLookParams& p = {}) {
    ActiveLookState st;
    return pan(st, tracks, 0.0, p) == 0.0 && st.looks == 0;
  };
  EXPECT_TRUE(none({track(1, kLensX, 2.0)})) << "2 m beside: the PTZ head's recall there is 0";
  EXPECT_TRUE(none({track(2, kLensX + 3.0, 1.5)})) << "27 degrees off: the wide head's view";
  EXPECT_TRUE(none({track(3, kLensX - 3.6, 0.5)})) << "behind, beyond the head's reach";
  HumanTrack found = track(4, kLensX, 3.5);
  found.camera_hits = 2;
  EXPECT_TRUE(none({found})) << "a head has found it";
  HumanTrack fresh = track(5, kLensX, 3.5);
  fresh.confirmed = false;
  EXPECT_TRUE(none({fresh})) << "not yet a track";
  ActiveLookParams off;
  off.enabled = false;
  EXPECT_TRUE(none({track(6, kLensX, 3.5)}, off));
  // Of two candidates, the nearer.
  ActiveLookState st;
  pan(st, {track(10, kLensX, 4.5), track(11, kLensX, -3.2)}, 0.0);
  EXPECT_EQ(st.target_id, 11);
}
