// The people detector (shared/perception/people_detector.hpp) on pictures of
// the simulated camera: a person in the open is found where the camera model
// drew them, an empty corridor gives no box, and bad options, a picture of
// the wrong type and a missing cascade are refused with their names.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "shared/perception/people_detector.hpp"
#include "sim/camera_view.hpp"
#include "tests/sim/world_text.hpp"

using namespace inspect;
using perception::DetectorMethod;
using perception::PeopleDetector;
using perception::PeopleDetectorOptions;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A 4 m wide corridor along +x, the robot at its start facing along it.
sim::World corridor() {
  return test::worldOf("walls:\n  - {points_m: [-1, -2,  20, -2]}\n  - {points_m: [-1, 2,  20, 2]}\n");
}

cv::Mat picture(const sim::World& w, const sim::CameraScene& s, std::vector<sim::PersonTruth>* truth = nullptr) {
  sim::CameraViewStyle style;
  style.noise_sigma = 3;
  sim::CameraView view(w, config::CameraMount{}, 640, 480, style);
  cv::Mat pic;
  view.render(s, 1000000, 1, pic);
  if (truth) *truth = view.peopleDrawn();
  return pic;
}

double iou(const cv::Rect& a, const cv::Rect& b) {
  const double i = (a & b).area();
  return i / (a.area() + b.area() - i);
}

}  // namespace

TEST(PeopleDetector, FindsAPersonInTheOpenWhereTheCameraDrewThem) {
  const sim::World w = corridor();
  sim::CameraScene s;
  // 5 m ahead, a little to the left, walking towards the robot.
  s.people.push_back({{5.2, 0.4}, 0.25, 2, kPi, 1.0, 0.3});
  std::vector<sim::PersonTruth> truth;
  const cv::Mat pic = picture(w, s, &truth);
  ASSERT_EQ(truth.size(), 1u);
  PeopleDetector hog({});
  const auto found = hog.detect(pic);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_GT(iou(found[0].box, truth[0].box), 0.5);
  EXPECT_FALSE(found[0].upper_body);
  // The same from a grey picture.
  cv::Mat grey;
  cv::cvtColor(pic, grey, cv::COLOR_BGR2GRAY);
  const auto again = hog.detect(grey);
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0].box, found[0].box);
}

TEST(PeopleDetector, TheFloorBandFindsTheSameAsTheWholePyramidWithLessSearch) {
  // The ground-plane constraint (PeopleDetectorOptions::floor_band): with a
  // height range nobody leaves, it searches the windows detectMultiScale
  // does and gives the very same boxes; with people's heights it still finds
  // people standing on the floor at 3-8 m.
  const sim::World w = corridor();
  perception::CameraPose cam;  // the simulated camera: config::CameraMount{}, tilt 0
  PeopleDetector whole({});
  PeopleDetectorOptions any;
  any.floor_band = true;
  any.floor_min_m = 1e-6;
  any.floor_max_m = 5.0;
  PeopleDetector everything(any);
  PeopleDetectorOptions band;
  band.floor_band = true;
  PeopleDetector floor(band);
  EXPECT_EQ(perception::describe(band), "hog x1 step 1.05 stride 8 thr 0.00 group 2 floor");
  int found = 0;
  for (const double x : {3.2, 4.2, 5.2, 6.5, 8.0}) {
    sim::CameraScene s;
    s.people.push_back({{x, 0.4}, 0.25, 2, kPi, 1.0, 0.3});
    std::vector<sim::PersonTruth> truth;
    const cv::Mat pic = picture(w, s, &truth);
    const auto a = whole.detect(pic), b = floor.detect(pic, &cam);
    // The pyramid rebuilt level by level, every floor row searched: the same boxes to the pixel.
    const auto c = everything.detect(pic, &cam);
    ASSERT_EQ(a.size(), c.size()) << "x " << x;
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].box, c[i].box) << "x " << x;
    ASSERT_EQ(b.size(), a.size()) << "x " << x;
    for (std::size_t i = 0; i < a.size(); ++i) {
      // The group's mean moves a pixel or two where a level's edge windows were left out.
      EXPECT_GT(iou(b[i].box, a[i].box), 0.9) << "x " << x;
      EXPECT_GT(iou(b[i].box, truth[0].box), 0.5) << "x " << x;
    }
    found += static_cast<int>(b.size());
  }
  EXPECT_GE(found, 4) << "people at 3-8 m in the open";
  // Without the picture's pose there is no floor to go by: the whole picture.
  sim::CameraScene s;
  s.people.push_back({{5.2, 0.4}, 0.25, 2, kPi, 1.0, 0.3});
  const cv::Mat pic = picture(w, s);
  EXPECT_EQ(floor.detect(pic).size(), whole.detect(pic).size());
}

TEST(PeopleDetector, AnEmptyCorridorGivesNoBox) {
  const sim::World w = corridor();
  for (const double pan : {-0.3, 0.0, 0.3}) {
    sim::CameraScene s;
    s.pan_rad = pan;
    PeopleDetector hog({});
    EXPECT_TRUE(hog.detect(picture(w, s)).empty()) << "pan " << pan;
  }
}

TEST(PeopleDetector, RefusesBadOptionsPicturesAndMissingCascades) {
  auto refused = [](auto change, const std::string& name) {
    PeopleDetectorOptions o;
    change(o);
    try {
      PeopleDetector d(o);
      ADD_FAILURE() << name << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  refused([](PeopleDetectorOptions& o) { o.upscale = 0.5; }, "upscale");
  refused([](PeopleDetectorOptions& o) { o.scale_step = 1.0; }, "scale_step");
  refused([](PeopleDetectorOptions& o) { o.stride_px = 5; }, "stride_px");
  refused([](PeopleDetectorOptions& o) { o.hit_threshold = NAN; }, "hit_threshold");
  refused([](PeopleDetectorOptions& o) { o.group_threshold = -1; }, "group_threshold");

  PeopleDetector hog({});
  EXPECT_THROW(hog.detect(cv::Mat(48, 64, CV_32FC1, cv::Scalar(0))), std::invalid_argument);
  EXPECT_TRUE(hog.detect(cv::Mat()).empty());

  PeopleDetectorOptions o;
  o.method = DetectorMethod::HaarFullBody;
  o.cascade_dir = "/nonexistent";
  try {
    PeopleDetector d(o);
    ADD_FAILURE() << "a missing cascade was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/haarcascades/haarcascade_fullbody.xml"), std::string::npos)
        << e.what();
  }
  DetectorMethod m;
  EXPECT_TRUE(perception::parseDetectorMethod("hog-daimler", m));
  EXPECT_EQ(m, DetectorMethod::HogDaimler);
  EXPECT_FALSE(perception::parseDetectorMethod("yolo", m));
  EXPECT_EQ(perception::methodName(DetectorMethod::HaarUpperBody), "haar-upperbody");
}
