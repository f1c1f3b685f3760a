// The simulated camera's picture (sim/camera_view.hpp): geometry checked
// against the pinhole model (a wall's foot row, a person's column, pan and
// tilt), shading by distance, occlusion, floor lines, and the time code that
// the latency measurements read. Pictures are compared with the same scene
// rendered without the thing under test; no timing.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "shared/video/timecode.hpp"
#include "sim/camera_view.hpp"
#include "sim/person_figure.hpp"
#include "tests/sim/world_text.hpp"

using namespace inspect;
using namespace inspect::sim;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kW = 640, kH = 480;
constexpr uint64_t kCapture = 123456789;
constexpr uint32_t kIndex = 42;

config::CameraMount mount() { return config::CameraMount{}; }  // 0.20 m ahead, 0.60 m up, 60 degrees

CameraScene atOrigin(double pan_deg = 0, double tilt_deg = 0) {
  CameraScene s;
  s.pan_rad = pan_deg * kPi / 180;
  s.tilt_rad = tilt_deg * kPi / 180;
  return s;
}

cv::Mat render(const World& w, const CameraScene& s, int width = kW, int height = kH, CameraViewStyle style = {}) {
  CameraView view(w, mount(), width, height, style);
  cv::Mat out;
  view.render(s, kCapture, kIndex, out);
  return out;
}

// A wall across the view at x = x_m, from y = -5 to 5.
World wallAt(double x_m) {
  return test::worldOf("walls:\n  - {from_m: [" + std::to_string(x_m) + ", -5], to_m: [" + std::to_string(x_m) +
                       ", 5]}\n");
}

// Columns (min, max, mean) where two pictures differ below the time code and
// above the caption; min > max when they do not.
struct Diff {
  int col_min = 1 << 30, col_max = -1, row_min = 1 << 30, row_max = -1;
  double col_mean = 0;
  long n = 0;
  bool any() const { return n > 0; }
};
Diff diff(const cv::Mat& a, const cv::Mat& b, int col_from = 0) {
  Diff d;
  double sum = 0;
  for (int r = 45; r < a.rows - 45; ++r)
    for (int c = col_from; c < a.cols; ++c)
      if (a.at<cv::Vec3b>(r, c) != b.at<cv::Vec3b>(r, c)) {
        d.col_min = std::min(d.col_min, c), d.col_max = std::max(d.col_max, c);
        d.row_min = std::min(d.row_min, r), d.row_max = std::max(d.row_max, r);
        sum += c + 0.5;
        ++d.n;
      }
  d.col_mean = d.n ? sum / static_cast<double>(d.n) : 0;
  return d;
}

double luma(const cv::Vec3b& p) { return 0.114 * p[0] + 0.587 * p[1] + 0.299 * p[2]; }

}  // namespace

TEST(CameraView, AWallAheadIsDarkerFurtherOffAndMeetsTheFloorWhereThePinholeSaysSo) {
  const World empty;
  const cv::Mat none = render(empty, atOrigin());
  CameraView view(empty, mount(), kW, kH);
  const double f = view.focalPx();
  EXPECT_NEAR(f, 320 / std::tan(30 * kPi / 180), 1e-9);
  double upper_luma[2] = {0, 0};
  int k = 0;
  for (const double x : {2.2, 6.2}) {
    const cv::Mat pic = render(wallAt(x), atOrigin());
    const double d = x - 0.2;  // from the lens
    // The wall's foot: the lowest row of the centre column that differs from
    // the empty world (floor there) is the row of height 0 at distance d.
    const int col = kW / 2;
    int lowest = -1;
    for (int r = kH - 46; r >= 45; --r)
      if (pic.at<cv::Vec3b>(r, col) != none.at<cv::Vec3b>(r, col)) {
        lowest = r;
        break;
      }
    const double foot = kH / 2.0 + f * 0.6 / d;
    EXPECT_NEAR(lowest + 0.5, foot, 1.5) << "wall at " << d << " m";
    // Brightness of the upper wall (1.2 m high) near the middle of the
    // picture (off the panel seam straight ahead).
    const int r = static_cast<int>(kH / 2.0 + f * (0.6 - 1.2) / d);
    double sum = 0;
    for (int dr = -2; dr <= 2; ++dr)
      for (int dc = -2; dc <= 2; ++dc) sum += luma(pic.at<cv::Vec3b>(r + dr, col + 30 + dc));
    upper_luma[k++] = sum / 25;
  }
  EXPECT_GT(upper_luma[0], upper_luma[1] + 20) << "near " << upper_luma[0] << " far " << upper_luma[1];
  EXPECT_GT(upper_luma[1], 60) << "far walls stay visible";
}

TEST(CameraView, AWallSeenObliquelyIsDarkerThanOneFacingTheLens) {
  // Through the same point ahead, once square on, once 70 degrees from it.
  const World square = wallAt(4.2);
  const double c20 = std::cos(20 * kPi / 180), s20 = std::sin(20 * kPi / 180);
  const World oblique = test::worldOf("walls:\n  - {from_m: [" + std::to_string(4.2 - 3 * c20) + ", " +
                                      std::to_string(-3 * s20) + "], to_m: [" + std::to_string(4.2 + 7 * c20) + ", " +
                                      std::to_string(7 * s20) + "]}\n");
  const cv::Mat a = render(square, atOrigin()), b = render(oblique, atOrigin());
  const int r = 150, c = kW / 2 + 30;
  EXPECT_GT(luma(a.at<cv::Vec3b>(r, c)), luma(b.at<cv::Vec3b>(r, c)) + 10);
}

TEST(CameraView, APersonAppearsInTheColumnOfTheirBearingStandingOnTheFloor) {
  const World empty;
  CameraScene with = atOrigin();
  with.people.push_back({{4.0, 1.5}, 0.25, 0});
  CameraView view(empty, mount(), kW, kH);
  cv::Mat b;
  view.render(with, kCapture, kIndex, b);
  const Diff d = diff(render(empty, atOrigin()), b);
  ASSERT_TRUE(d.any());
  const double f = view.focalPx();
  const double x = 4.0 - 0.2, y = 1.5;  // from the lens: ahead, left
  const double expected_col = kW / 2.0 - f * y / x;
  EXPECT_NEAR(*view.columnOf(with, {4.0, 1.5}), expected_col, 1e-9);
  // Facing +x (away from the camera), standing: symmetric about the body's axis.
  EXPECT_NEAR((d.col_min + d.col_max + 1) / 2.0, expected_col, 2.0);
  const PersonLook look = personLook(0, 0);
  // Shoulders and arms: about a quarter of the height wide; feet on the floor.
  EXPECT_NEAR(d.col_max + 1 - d.col_min, 0.27 * look.height_m * look.build * f / x, 0.06 * look.height_m * f / x);
  EXPECT_NEAR(d.row_max + 0.5, kH / 2.0 + f * 0.6 / x, 1.5);
  EXPECT_NEAR(d.row_min, kH / 2.0 + f * (0.6 - look.height_m) / x, 2.0) << "the top of the head at their height";
  // The truth is the figure's box, as drawn.
  ASSERT_EQ(view.peopleDrawn().size(), 1u);
  const PersonTruth& t = view.peopleDrawn()[0];
  EXPECT_EQ(t.box, cv::Rect(d.col_min, d.row_min, d.col_max + 1 - d.col_min, d.row_max + 1 - d.row_min));
  EXPECT_NEAR(t.full_box.x, t.box.x, 2.0);
  EXPECT_NEAR(t.full_box.height, t.box.height, 2.0);
  EXPECT_NEAR(t.distance_m, std::hypot(x, y), 1e-9);
  EXPECT_NEAR(t.bearing_rad, std::atan2(y, x), 1e-9);
  EXPECT_GT(t.visible, 0.97);
  EXPECT_TRUE(t.feet_in_view);
  EXPECT_TRUE(t.head_in_view);
}

TEST(CameraView, PeopleAreSeenFromTheFrontTheSideOrTheBackAndWalkersSwingTheirLegs) {
  const World empty;
  // One person 5 m ahead; headings: towards the camera (pi), away (0), across (pi/2).
  auto pictureOf = [&](double heading, double speed, double walked) {
    CameraScene s = atOrigin();
    s.people.push_back({{5.2, 0.0}, 0.25, 3, heading, speed, walked});
    return render(empty, s);
  };
  const cv::Mat none = render(empty, atOrigin());
  const cv::Mat front = pictureOf(kPi, 0, 0), back = pictureOf(0, 0, 0), side = pictureOf(kPi / 2, 0, 0);
  const Diff df = diff(none, front), db = diff(none, back), ds = diff(none, side);
  ASSERT_TRUE(df.any() && db.any() && ds.any());
  const int wf = df.col_max - df.col_min, ws = ds.col_max - ds.col_min;
  EXPECT_LT(ws, 0.8 * wf) << "from the side a person is narrower than from the front";
  // Front and back have the same outline; the head differs (a face, or hair).
  EXPECT_NEAR(db.col_max - db.col_min, wf, 2);
  const int head_row = df.row_min + (df.row_max - df.row_min) / 14;  // the upper face
  long differ = 0;
  for (int c = df.col_min; c <= df.col_max; ++c) differ += front.at<cv::Vec3b>(head_row, c) != back.at<cv::Vec3b>(head_row, c);
  EXPECT_GT(differ, 3) << "front and back differ at the face";
  // Walking across the view: legs together at phase 0, apart a quarter cycle on.
  const PersonLook look = personLook(0, 3);
  const double cycle = 0.83 * look.height_m;
  const cv::Mat together = pictureOf(kPi / 2, 1.4, 0.0), apart = pictureOf(kPi / 2, 1.4, cycle / 4);
  auto feetWidth = [&](const cv::Mat& pic) {
    const Diff d = diff(none, pic);
    int c0 = kW, c1 = -1;
    for (int r = d.row_max - 3; r <= d.row_max; ++r)
      for (int c = 0; c < kW; ++c)
        if (pic.at<cv::Vec3b>(r, c) != none.at<cv::Vec3b>(r, c)) c0 = std::min(c0, c), c1 = std::max(c1, c);
    return c1 - c0;
  };
  EXPECT_GT(feetWidth(apart), feetWidth(together) + 8) << "a stride apart";
  // Pure: the same gait phase gives the same picture.
  EXPECT_EQ(cv::norm(apart, pictureOf(kPi / 2, 1.4, cycle / 4), cv::NORM_INF), 0);
}

TEST(CameraView, EachPersonLooksTheirOwnFromTheSeed) {
  double sum = 0, sum2 = 0, lo = 9, hi = 0;
  int shirts_differ = 0;
  constexpr int kN = 400;
  for (int i = 0; i < kN; ++i) {
    const PersonLook a = personLook(7, i);
    const PersonLook again = personLook(7, i);
    EXPECT_EQ(a.height_m, again.height_m);
    EXPECT_EQ(a.shirt, again.shirt);
    sum += a.height_m;
    sum2 += a.height_m * a.height_m;
    lo = std::min(lo, a.height_m);
    hi = std::max(hi, a.height_m);
    EXPECT_GE(a.build, 0.85);
    EXPECT_LE(a.build, 1.2);
    shirts_differ += personLook(8, i).shirt != a.shirt;
  }
  const double mean = sum / kN, sd = std::sqrt(sum2 / kN - mean * mean);
  EXPECT_NEAR(mean, 1.75, 0.02);
  EXPECT_NEAR(sd, 0.09, 0.02);
  EXPECT_GE(lo, 1.50);
  EXPECT_LE(hi, 1.98);
  EXPECT_GT(shirts_differ, kN / 2) << "another seed dresses people otherwise";
}

TEST(CameraView, TheTruthSaysHowMuchOfEachPersonIsShown) {
  const World empty;
  CameraView view(empty, mount(), kW, kH);
  cv::Mat pic;
  // One in front of another on the same bearing: the far one is mostly hidden.
  CameraScene s = atOrigin();
  s.people.push_back({{6.2, 0.0}, 0.25, 1});
  s.people.push_back({{3.2, 0.0}, 0.25, 2});
  view.render(s, kCapture, kIndex, pic);
  ASSERT_EQ(view.peopleDrawn().size(), 2u);
  const auto& far = view.peopleDrawn()[0];
  const auto& near = view.peopleDrawn()[1];
  EXPECT_EQ(far.index, 1) << "drawn far to near";
  EXPECT_LT(far.visible, 0.35);
  EXPECT_GT(near.visible, 0.97);
  // Half out of the picture at its edge: about half shown, the box cut to the picture.
  const double f = view.focalPx();
  const double y_edge = 4.0 * (kW / 2.0) / f;  // the picture's left edge, 4 m from the lens
  CameraScene edge = atOrigin();
  edge.people.push_back({{4.2, y_edge}, 0.25, 1});
  view.render(edge, kCapture, kIndex, pic);
  ASSERT_EQ(view.peopleDrawn().size(), 1u);
  EXPECT_NEAR(view.peopleDrawn()[0].visible, 0.5, 0.15);
  EXPECT_EQ(view.peopleDrawn()[0].box.x, 0);
  EXPECT_LT(view.peopleDrawn()[0].full_box.x, 0);
  // Close up (1.5 m), the head is above the picture at tilt 0; tilted up 20 degrees it is in.
  CameraScene close = atOrigin();
  close.people.push_back({{1.7, 0.0}, 0.25, 1});
  view.render(close, kCapture, kIndex, pic);
  EXPECT_FALSE(view.peopleDrawn()[0].head_in_view);
  EXPECT_TRUE(view.peopleDrawn()[0].feet_in_view);
  close.tilt_rad = 20 * kPi / 180;
  view.render(close, kCapture, kIndex, pic);
  EXPECT_TRUE(view.peopleDrawn()[0].head_in_view);
  // Behind the lens: not drawn, not in the truth.
  CameraScene behind = atOrigin();
  behind.people.push_back({{-2.0, 0.0}, 0.25, 1});
  view.render(behind, kCapture, kIndex, pic);
  EXPECT_TRUE(view.peopleDrawn().empty());
}

TEST(CameraView, SensorNoiseAndMotionBlurAreSeededAndLeaveTheTimeCodeReadable) {
  const World w = wallAt(4.2);
  CameraViewStyle real;
  real.noise_sigma = 4.0;
  CameraScene s = atOrigin();
  const cv::Mat clean = render(w, s), noisy = render(w, s, kW, kH, real);
  // Mean |noise| of a Gaussian is 0.8 sigma (a little less where it saturates).
  cv::Mat d;
  cv::absdiff(clean(cv::Rect(0, 60, kW, 300)), noisy(cv::Rect(0, 60, kW, 300)), d);
  const double mean_abs = cv::mean(d)[0];
  EXPECT_NEAR(mean_abs, 0.8 * 4.0, 0.5);
  EXPECT_EQ(cv::norm(noisy, render(w, s, kW, kH, real), cv::NORM_INF), 0) << "seeded: the same picture again";
  const auto code = video::readTimecode(noisy);
  ASSERT_TRUE(code);
  EXPECT_EQ(code->capture_us, kCapture);
  // Motion blur: turning at 1 rad/s over 10 ms smears the panel seam (a vertical
  // line straight ahead) over f x 0.01 = 5.5 pixels.
  CameraViewStyle blur;
  blur.exposure_ms = 10;
  s.yaw_rate_rad_s = 1.0;
  const cv::Mat sharp = render(w, s), smeared = render(w, s, kW, kH, blur);
  auto strongestStep = [](const cv::Mat& pic, int row) {
    int best = 0;
    for (int c = 1; c < pic.cols; ++c)
      best = std::max(best, std::abs(static_cast<int>(pic.at<cv::Vec3b>(row, c)[1]) - pic.at<cv::Vec3b>(row, c - 1)[1]));
    return best;
  };
  EXPECT_LT(strongestStep(smeared, 150), strongestStep(sharp, 150) * 0.6);
  CameraViewStyle bad;
  bad.noise_sigma = -1;
  EXPECT_THROW(CameraView(World{}, mount(), kW, kH, bad), std::invalid_argument);
  bad = {};
  bad.exposure_ms = 500;
  EXPECT_THROW(CameraView(World{}, mount(), kW, kH, bad), std::invalid_argument);
}

TEST(CameraView, PeopleBehindAWallAreHiddenAndPeopleBehindALowBoxShowAboveIt) {
  CameraScene with = atOrigin();
  with.people.push_back({{5.0, 0.0}, 0.25, 1});
  const World wall = wallAt(3.0);
  EXPECT_FALSE(diff(render(wall, atOrigin()), render(wall, with)).any());

  // A box lower than the lens (0.4 m high, 0.6 m wide) 2 m ahead: the
  // person's legs are behind it, the body and head above it are seen, and the
  // box's top (seen from above) is painted between its front and back edges.
  const World box = test::worldOf("obstacles:\n  - vertices_m: [2.2, -0.3,  2.8, -0.3,  2.8, 0.3,  2.2, 0.3]\n");
  CameraViewStyle low;
  low.obstacle_height_m = 0.4;
  const cv::Mat without = render(box, atOrigin(), kW, kH, low), shown = render(box, with, kW, kH, low);
  const Diff d = diff(without, shown);
  ASSERT_TRUE(d.any());
  CameraView view(box, mount(), kW, kH, low);
  const double f = view.focalPx();
  const double box_top_front = kH / 2.0 + f * (0.6 - 0.4) / 2.0;  // the box's near top edge, 2 m from the lens
  EXPECT_LT(d.row_max, box_top_front) << "the legs are hidden by the box";
  EXPECT_NEAR(d.row_min, kH / 2.0 + f * (0.6 - 1.75) / 4.8, 3.0) << "the head is seen";
  // The box top: rows between the top edges of its near (2.0 m) and far (2.6 m) faces.
  const cv::Mat empty_pic = render(World{}, atOrigin(), kW, kH, low);
  const int top_row = static_cast<int>((kH / 2.0 + f * 0.2 / 2.0 + kH / 2.0 + f * 0.2 / 2.6) / 2);
  EXPECT_NE(without.at<cv::Vec3b>(top_row, kW / 2), empty_pic.at<cv::Vec3b>(top_row, kW / 2));
  EXPECT_GT(luma(without.at<cv::Vec3b>(top_row, kW / 2)),
            luma(without.at<cv::Vec3b>(static_cast<int>(box_top_front) + 20, kW / 2)))
      << "the top (lit from above) is lighter than the front face";
}

TEST(CameraView, PanTurnsTheViewAndTiltMovesTheHorizon) {
  // A short wall piece 4 m ahead of the lens, 0.4 m wide.
  const World piece = test::worldOf("walls:\n  - {from_m: [4.2, -0.2], to_m: [4.2, 0.2]}\n");
  const World empty;
  CameraView view(piece, mount(), kW, kH);
  const double f = view.focalPx();
  double centre[3];
  int i = 0;
  for (const double pan : {0.0, 10.0, -15.0}) {
    const Diff d = diff(render(empty, atOrigin(pan)), render(piece, atOrigin(pan)));
    ASSERT_TRUE(d.any()) << pan;
    centre[i] = (d.col_min + d.col_max + 1) / 2.0;
    // Panning left (CCW) by a moves a thing straight ahead of the robot to the right by f tan(a).
    EXPECT_NEAR(centre[i], kW / 2.0 + f * std::tan(pan * kPi / 180), 2.0) << pan;
    EXPECT_NEAR(*view.columnOf(atOrigin(pan), {4.2, 0.0}), kW / 2.0 + f * std::tan(pan * kPi / 180), 1e-9);
    ++i;
  }
  EXPECT_GT(centre[1], centre[0] + 80);
  EXPECT_LT(centre[2], centre[0] - 120);
  // Out of view when panned far enough.
  EXPECT_FALSE(diff(render(empty, atOrigin(60)), render(piece, atOrigin(60))).any());

  // Tilt: up 10 degrees moves the horizon and the wall's foot down by f tan(10).
  EXPECT_NEAR(view.horizonRow(atOrigin(0, 10)), kH / 2.0 + f * std::tan(10 * kPi / 180), 1e-9);
  EXPECT_NEAR(view.horizonRow(atOrigin(0, -10)), kH / 2.0 - f * std::tan(10 * kPi / 180), 1e-9);
  const Diff level = diff(render(empty, atOrigin(0, 0)), render(piece, atOrigin(0, 0)));
  const Diff up = diff(render(empty, atOrigin(0, 10)), render(piece, atOrigin(0, 10)));
  EXPECT_NEAR(up.row_max - level.row_max, f * std::tan(10 * kPi / 180), 2.0);
}

TEST(CameraView, FloorLinesLieOnTheFloor) {
  // A 5 cm line straight ahead from under the robot to 8 m.
  const World w = test::worldOf("floor_lines:\n  - {from_m: [0, 0], to_m: [8, 0], width_m: 0.05}\n");
  const cv::Mat a = render(World{}, atOrigin()), b = render(w, atOrigin());
  CameraView view(w, mount(), kW, kH);
  const double f = view.focalPx();
  const int row = static_cast<int>(kH / 2.0 + f * 0.6 / 2.0);  // the floor 2 m from the lens
  const cv::Vec3b on = b.at<cv::Vec3b>(row, kW / 2);
  EXPECT_NE(on, a.at<cv::Vec3b>(row, kW / 2));
  EXPECT_GT(on[2], on[0] + 60) << "yellow: red and green well above blue";
  EXPECT_GT(on[1], on[0] + 60);
  // 5 cm at 2 m is ~14 px: 20 px to the side is floor again.
  EXPECT_EQ(b.at<cv::Vec3b>(row, kW / 2 + 20), a.at<cv::Vec3b>(row, kW / 2 + 20));
  // Nothing of it above the horizon, and none beyond its end (8 m).
  const Diff d = diff(a, b);
  EXPECT_GT(d.row_min + 0.5, kH / 2.0 + f * 0.6 / 8.0 - 1.5);
}

TEST(CameraView, TheTimeCodeAndTheCaptionSurviveTheScene) {
  const World w = test::worldOf(
      "walls:\n  - {points_m: [-1, -2,  9, -2,  9, 2,  -1, 2], closed: true}\n"
      "obstacles:\n  - vertices_m: [3, 0.5,  4, 0.5,  4, 1.5,  3, 1.5]\n"
      "floor_lines:\n  - {from_m: [0, 0], to_m: [8, 0]}\n");
  CameraScene s = atOrigin(20, -10);
  s.people.push_back({{2.0, 0.0}, 0.25, 0});
  for (const auto& [wd, ht] : {std::pair{640, 480}, std::pair{320, 240}, std::pair{1280, 720}}) {
    CameraView view(w, mount(), wd, ht);
    cv::Mat pic;
    view.render(s, kCapture, kIndex, pic);
    ASSERT_EQ(pic.cols, wd);
    ASSERT_EQ(pic.rows, ht);
    ASSERT_EQ(pic.type(), CV_8UC3);
    const auto code = video::readTimecode(pic);
    ASSERT_TRUE(code) << wd << "x" << ht;
    EXPECT_EQ(code->capture_us, kCapture);
    EXPECT_EQ(code->frame_index, kIndex);
    // The same scene gives the same picture (a pure function of its inputs).
    cv::Mat again;
    view.render(s, kCapture, kIndex, again);
    EXPECT_EQ(cv::norm(pic, again, cv::NORM_INF), 0);
  }
}

TEST(CameraView, RefusesSizesItCannotDraw) {
  EXPECT_THROW(CameraView(World{}, mount(), 32, 480), std::invalid_argument);
  EXPECT_THROW(CameraView(World{}, mount(), 640, 5000), std::invalid_argument);
}
