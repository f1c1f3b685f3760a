// Keyboard teleop: step gauge, clamping, the hold-mode deadman, key decoding.
#include <gtest/gtest.h>

#include "pc_server/terminal/key_decoder.hpp"
#include "pc_server/terminal/keyboard_teleop.hpp"

using namespace inspect::server;
using Key = KeyboardTeleop::Key;
using Mode = KeyboardTeleop::Mode;

TEST(KeyboardTeleopStep, KeysStepAndSpaceZeroes) {
  KeyboardTeleop kt(Mode::kStep);
  EXPECT_TRUE(kt.onKey(Key::kForward, 0));
  EXPECT_TRUE(kt.onKey(Key::kForward, 0.1));
  EXPECT_TRUE(kt.onKey(Key::kLeft, 0.2));
  EXPECT_DOUBLE_EQ(kt.v(), 0.10);
  EXPECT_DOUBLE_EQ(kt.w(), 0.1);
  EXPECT_TRUE(kt.onKey(Key::kBack, 0.3));
  EXPECT_TRUE(kt.onKey(Key::kBack, 0.4));
  EXPECT_EQ(kt.v(), 0.0) << "stepping back lands exactly on zero";
  EXPECT_FALSE(kt.tick(100)) << "step mode has no deadman";
  EXPECT_DOUBLE_EQ(kt.w(), 0.1);
  EXPECT_TRUE(kt.onKey(Key::kZero, 100));
  EXPECT_EQ(kt.v(), 0.0);
  EXPECT_EQ(kt.w(), 0.0);
  EXPECT_FALSE(kt.onKey(Key::kOther, 101));
  EXPECT_FALSE(kt.finished());
}

TEST(KeyboardTeleopStep, ClampsToLimits) {
  KeyboardTeleop kt(Mode::kStep);
  for (int i = 0; i < 40; ++i) kt.onKey(Key::kForward, i);
  for (int i = 0; i < 40; ++i) kt.onKey(Key::kRight, i);
  EXPECT_NEAR(kt.v(), 1.0, 1e-12);
  EXPECT_NEAR(kt.w(), -2.0, 1e-12);
  EXPECT_FALSE(kt.onKey(Key::kForward, 50)) << "already at the limit";
  EXPECT_EQ(kt.gauge(), "v [     |=====] +1.00 m/s  w [=====|     ] -2.00 rad/s");
}

TEST(KeyboardTeleopStep, LeavingZeroes) {
  KeyboardTeleop kt(Mode::kStep);
  kt.onKey(Key::kForward, 0);
  EXPECT_TRUE(kt.onKey(Key::kLeave, 1));
  EXPECT_TRUE(kt.finished());
  EXPECT_EQ(kt.v(), 0.0);
}

TEST(KeyboardTeleopHold, SinglePressStopsAfterFirstRepeatTimeout) {
  KeyboardTeleop kt(Mode::kHold);
  EXPECT_TRUE(kt.onKey(Key::kForward, 10.0));
  EXPECT_DOUBLE_EQ(kt.v(), 0.3);
  EXPECT_FALSE(kt.tick(10.25)) << "a tap drives until the first-repeat timeout";
  EXPECT_TRUE(kt.tick(10.31)) << "operator silence stops within 300 ms of the last key";
  EXPECT_EQ(kt.v(), 0.0);
}

TEST(KeyboardTeleopHold, HeldKeyDrivesAndReleaseStopsWithin300ms) {
  KeyboardTeleop kt(Mode::kHold);
  double t = 0;
  kt.onKey(Key::kLeft, t);
  t += 0.5;  // auto-repeat delay
  // 30 Hz auto-repeat for 2 s: no stutter.
  for (; t < 2.5; t += 1.0 / 30) {
    kt.onKey(Key::kLeft, t);
    EXPECT_FALSE(kt.tick(t + 0.02));
    EXPECT_DOUBLE_EQ(kt.w(), 1.0);
  }
  // Released after the last repeat: find when the console (ticking every 20 ms) zeroes it.
  const double released = t - 1.0 / 30;
  double zeroed_after = -1;
  for (double dt = 0.02; dt < 1.0; dt += 0.02) {
    if (kt.tick(released + dt)) {
      zeroed_after = dt;
      break;
    }
  }
  EXPECT_GT(zeroed_after, 0.19);
  EXPECT_LE(zeroed_after, 0.3);
  EXPECT_EQ(kt.w(), 0.0);
}

TEST(KeyboardTeleopHold, OtherKeySwitchesDirectionAndRestartsRepeatDetection) {
  KeyboardTeleop kt(Mode::kHold);
  kt.onKey(Key::kForward, 0);
  kt.onKey(Key::kForward, 0.4);  // repeat seen
  EXPECT_TRUE(kt.onKey(Key::kBack, 0.45));
  EXPECT_DOUBLE_EQ(kt.v(), -0.3);
  EXPECT_FALSE(kt.tick(0.45 + 0.25)) << "new key: back to the 300 ms first-repeat timeout";
  EXPECT_TRUE(kt.tick(0.45 + 0.31));
}

TEST(KeyboardTeleopHold, SpaceZeroesAtOnce) {
  KeyboardTeleop kt(Mode::kHold);
  kt.onKey(Key::kRight, 0);
  EXPECT_TRUE(kt.onKey(Key::kZero, 0.1));
  EXPECT_EQ(kt.w(), 0.0);
  EXPECT_FALSE(kt.tick(5));
}

TEST(KeyDecoder, LettersArrowsAndEscape) {
  KeyDecoder d;
  EXPECT_EQ(d.feed("wsad q"),
            (std::vector<Key>{Key::kForward, Key::kBack, Key::kLeft, Key::kRight, Key::kZero, Key::kLeave}));
  EXPECT_EQ(d.feed("\x1b[A\x1b[B\x1b[C\x1b[D\x1bOA"),
            (std::vector<Key>{Key::kForward, Key::kBack, Key::kRight, Key::kLeft, Key::kForward}));
  // A sequence split across reads.
  EXPECT_TRUE(d.feed("\x1b").empty());
  EXPECT_TRUE(d.pending());
  EXPECT_EQ(d.feed("[A"), std::vector<Key>{Key::kForward});
  // A lone Esc: known only when nothing follows.
  EXPECT_TRUE(d.feed("\x1b").empty());
  EXPECT_EQ(d.flush(), std::vector<Key>{Key::kLeave});
  EXPECT_FALSE(d.pending());
  // Other sequences (F5, Delete) are ignored keys.
  EXPECT_EQ(d.feed("\x1b[15~\x1b[3~z"), (std::vector<Key>{Key::kOther, Key::kOther, Key::kOther}));
}
