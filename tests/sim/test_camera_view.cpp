// The simulated camera's picture (sim/camera_view.hpp): geometry checked
// against the pinhole model (a wall's foot row, a person's column, pan and
// tilt), shading by distance, occlusion, floor lines, and the time code that
// the latency measurements read. Pictures are compared with the same scene
// rendered without the thing under test; no timing.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include <opencv2/core.hpp>

#include "shared/video/timecode.hpp"
#include "sim/camera_view.hpp"
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
  const cv::Mat a = render(empty, atOrigin()), b = render(empty, with);
  const Diff d = diff(a, b);
  ASSERT_TRUE(d.any());
  CameraView view(empty, mount(), kW, kH);
  const double f = view.focalPx();
  const double x = 4.0 - 0.2, y = 1.5;  // from the lens: ahead, left
  const double expected_col = kW / 2.0 - f * y / x;
  EXPECT_NEAR(*view.columnOf(with, {4.0, 1.5}), expected_col, 1e-9);
  EXPECT_NEAR((d.col_min + d.col_max + 1) / 2.0, expected_col, 2.0);
  // As wide as the shoulders (0.8 x radius each side), feet on the floor.
  EXPECT_NEAR(d.col_max + 1 - d.col_min, 2 * 0.2 * f / x, 3.0);
  EXPECT_NEAR(d.row_max + 0.5, kH / 2.0 + f * 0.6 / x, 1.5);
  // A person 1.75 m tall: the head's top.
  EXPECT_NEAR(d.row_min, kH / 2.0 + f * (0.6 - 1.75) / x, 3.0);
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
