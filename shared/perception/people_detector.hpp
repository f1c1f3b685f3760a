#pragma once
// People in a camera picture, found with a detector that Debian ships
// (OpenCV 4.6's objdetect, cascades from opencv-data): a HOG + linear SVM
// people detector (Dalal and Triggs' 64x128 window, or the Daimler 48x96
// one) or a Haar cascade (full body, upper body). bench_people measures
// them on the simulator's people and on real footage; docs/human-awareness.md
// gives the figures and the choice. Not thread-safe: one detector per thread.
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

#include "shared/perception/camera_geometry.hpp"

namespace inspect::perception {

enum class DetectorMethod { Hog, HogDaimler, HaarFullBody, HaarUpperBody };

/// Sets `out` from "hog", "hog-daimler", "haar-fullbody" or "haar-upperbody";
/// false (out unchanged) for anything else.
bool parseDetectorMethod(std::string_view text, DetectorMethod& out);
std::string_view methodName(DetectorMethod m);

struct PeopleDetectorOptions {
  DetectorMethod method = DetectorMethod::Hog;
  double upscale = 1.0;         // the picture is resized by this first (1 - 3): small people reach the window
  double scale_step = 1.05;     // the image pyramid's step (1.01 - 2)
  int stride_px = 8;            // HOG: window stride in the (upscaled) picture (4, 8 or 16)
  double hit_threshold = 0.0;   // HOG: the SVM's margin for a window to count
  int group_threshold = 2;      // windows that must agree (0: every window is a box)
  /// HOG, given the picture's CameraPose: search only the windows whose
  /// person would stand on the floor and be floor_min_m - floor_max_m tall
  /// (the ground-plane constraint); each pyramid level is cut to those rows.
  bool floor_band = false;
  double floor_min_m = 0.8, floor_max_m = 2.8;
  std::string cascade_dir = "/usr/share/opencv4";  // opencv-data's haarcascades/ live here
};

/// The options as one line ("hog x1 step 1.05 stride 8 thr 0.00 group 2").
std::string describe(const PeopleDetectorOptions& o);

/// One person found.
struct PersonBox {
  cv::Rect box;        // the whole person (upper-body methods: the head and shoulders), picture pixels
  double score = 0.0;  // HOG: the SVM's margin; cascades: the number of windows that agreed
  bool upper_body = false;
};

class PeopleDetector {
 public:
  /// Throws std::invalid_argument naming the option out of range, and
  /// std::runtime_error naming the file when a cascade cannot be loaded.
  explicit PeopleDetector(PeopleDetectorOptions options);
  ~PeopleDetector();
  PeopleDetector(PeopleDetector&&) noexcept;
  PeopleDetector& operator=(PeopleDetector&&) noexcept;

  /// The people in a BGR (CV_8UC3) or grey (CV_8UC1) picture, boxes in its
  /// pixels and cut to it. Throws std::invalid_argument for another type.
  /// `cam`: where the picture was taken (floor_band needs it; without it the
  /// whole picture is searched).
  std::vector<PersonBox> detect(const cv::Mat& picture, const CameraPose* cam = nullptr);

  const PeopleDetectorOptions& options() const { return options_; }

 private:
  struct Impl;
  PeopleDetectorOptions options_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace inspect::perception
