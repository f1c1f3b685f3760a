#include "shared/perception/people_detector.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <opencv2/imgproc.hpp>
#include <opencv2/objdetect.hpp>

namespace inspect::perception {

namespace {

struct Named {
  DetectorMethod method;
  std::string_view name;
};
constexpr Named kMethods[] = {{DetectorMethod::Hog, "hog"},
                              {DetectorMethod::HogDaimler, "hog-daimler"},
                              {DetectorMethod::HaarFullBody, "haar-fullbody"},
                              {DetectorMethod::HaarUpperBody, "haar-upperbody"}};

bool isHog(DetectorMethod m) { return m == DetectorMethod::Hog || m == DetectorMethod::HogDaimler; }

// The person inside a HOG window: the window has a margin round the person
// (16 of 128 rows above and below in Dalal and Triggs' training set), as
// OpenCV's peopledetect sample trims it.
cv::Rect trimWindow(const cv::Rect2d& r) {
  return cv::Rect(static_cast<int>(std::lround(r.x + 0.1 * r.width)), static_cast<int>(std::lround(r.y + 0.07 * r.height)),
                  static_cast<int>(std::lround(0.8 * r.width)), static_cast<int>(std::lround(0.8 * r.height)));
}

// The person inside a window of height h at row y: head and feet rows, as trimWindow.
constexpr double kHeadInWindow = 0.07, kFeetInWindow = 0.87;

/// HOG's image pyramid as HOGDescriptor::detectMultiScale builds it (its
/// scales, level sizes and window rounding, OpenCV 4.6), each level searched
/// only in the window rows whose person would stand on the floor and be
/// [min_m, max_m] tall (`cam`: the picture's, `up` its upscale); the same
/// grouping after. Levels are cut with rowRange: HOG's gradients read the
/// rows beyond the cut (locateROI), so a window's score is the full level's.
void floorBandHog(const cv::HOGDescriptor& hog, const cv::Mat& img, double up, const CameraPose& cam,
                  const PeopleDetectorOptions& o, std::vector<cv::Rect>& found, std::vector<double>& weights,
                  cv::Mat& level) {
  const cv::Size win = hog.winSize, stride(o.stride_px, o.stride_px);
  std::vector<cv::Point> locations;
  std::vector<double> hits;
  double scale = 1.0;
  for (int l = 0; l < hog.nlevels; ++l, scale *= o.scale_step) {
    const cv::Size sz(cvRound(img.cols / scale), cvRound(img.rows / scale));
    if (sz.width < win.width || sz.height < win.height) break;
    const double to_picture = scale / up;  // level pixels -> the picture's
    int k_lo = -1, k_hi = -1;
    for (int k = 0; k * stride.height + win.height <= sz.height; ++k) {
      const double top = k * stride.height * to_picture, h = win.height * to_picture;
      const double height_m = standingHeightM(top + kFeetInWindow * h, top + kHeadInWindow * h, cam);
      if (!(height_m >= o.floor_min_m && height_m <= o.floor_max_m)) continue;
      if (k_lo < 0) k_lo = k;
      k_hi = k;
    }
    if (k_lo < 0) continue;
    if (sz == img.size())
      level = img;
    else
      cv::resize(img, level, sz, 0, 0, cv::INTER_LINEAR_EXACT);
    // One window row of margin each side, on the stride's grid.
    const int r0 = std::max(0, (k_lo - 1) * stride.height);
    const int r1 = std::min(sz.height, (k_hi + 1) * stride.height + win.height);
    hog.detect(level.rowRange(r0, r1), locations, hits, o.hit_threshold, stride, cv::Size(0, 0));
    const cv::Size scaled_win(cvRound(win.width * scale), cvRound(win.height * scale));
    for (std::size_t j = 0; j < locations.size(); ++j) {
      if (hits[j] < o.hit_threshold) continue;
      found.emplace_back(cvRound(locations[j].x * scale), cvRound((locations[j].y + r0) * scale), scaled_win.width,
                         scaled_win.height);
      weights.push_back(hits[j]);
    }
  }
  hog.groupRectangles(found, weights, o.group_threshold, 0.2);
}

}  // namespace

bool parseDetectorMethod(std::string_view text, DetectorMethod& out) {
  for (const auto& m : kMethods)
    if (m.name == text) {
      out = m.method;
      return true;
    }
  return false;
}

std::string_view methodName(DetectorMethod m) {
  for (const auto& n : kMethods)
    if (n.method == m) return n.name;
  return "?";
}

std::string describe(const PeopleDetectorOptions& o) {
  char buf[160];
  if (isHog(o.method))
    std::snprintf(buf, sizeof buf, "%s x%.3g step %.3g stride %d thr %.2f group %d%s", std::string(methodName(o.method)).c_str(),
                  o.upscale, o.scale_step, o.stride_px, o.hit_threshold, o.group_threshold,
                  o.floor_band ? " floor" : "");
  else
    std::snprintf(buf, sizeof buf, "%s x%.3g step %.3g neighbours %d", std::string(methodName(o.method)).c_str(), o.upscale,
                  o.scale_step, o.group_threshold);
  return buf;
}

struct PeopleDetector::Impl {
  cv::HOGDescriptor hog;
  cv::CascadeClassifier cascade;
  cv::Mat grey, scaled, level;
};

PeopleDetector::PeopleDetector(PeopleDetectorOptions o) : options_(std::move(o)), impl_(std::make_unique<Impl>()) {
  if (!(options_.upscale >= 1.0 && options_.upscale <= 3.0))
    throw std::invalid_argument("people detector: upscale " + std::to_string(options_.upscale) + " outside [1, 3]");
  if (!(options_.scale_step >= 1.01 && options_.scale_step <= 2.0))
    throw std::invalid_argument("people detector: scale_step " + std::to_string(options_.scale_step) + " outside [1.01, 2]");
  if (options_.stride_px != 4 && options_.stride_px != 8 && options_.stride_px != 16)
    throw std::invalid_argument("people detector: stride_px " + std::to_string(options_.stride_px) + " is not 4, 8 or 16");
  if (!(options_.hit_threshold >= -1.0 && options_.hit_threshold <= 3.0))
    throw std::invalid_argument("people detector: hit_threshold " + std::to_string(options_.hit_threshold) +
                                " outside [-1, 3]");
  if (!(options_.floor_min_m > 0 && options_.floor_min_m < options_.floor_max_m && options_.floor_max_m <= 5))
    throw std::invalid_argument("people detector: the floor band's heights " + std::to_string(options_.floor_min_m) +
                                " - " + std::to_string(options_.floor_max_m) + " m are not 0 < min < max <= 5");
  if (options_.group_threshold < 0 || options_.group_threshold > 20)
    throw std::invalid_argument("people detector: group_threshold " + std::to_string(options_.group_threshold) +
                                " outside [0, 20]");
  switch (options_.method) {
    case DetectorMethod::Hog:
      impl_->hog.setSVMDetector(cv::HOGDescriptor::getDefaultPeopleDetector());
      break;
    case DetectorMethod::HogDaimler:
      impl_->hog = cv::HOGDescriptor(cv::Size(48, 96), cv::Size(16, 16), cv::Size(8, 8), cv::Size(8, 8), 9);
      impl_->hog.setSVMDetector(cv::HOGDescriptor::getDaimlerPeopleDetector());
      break;
    case DetectorMethod::HaarFullBody:
    case DetectorMethod::HaarUpperBody: {
      const std::string file = options_.cascade_dir + "/haarcascades/" +
                               (options_.method == DetectorMethod::HaarFullBody ? "haarcascade_fullbody.xml"
                                                                                : "haarcascade_upperbody.xml");
      if (!impl_->cascade.load(file))
        throw std::runtime_error("people detector: cannot load the cascade " + file +
                                 " (Debian's opencv-data installs it)");
      break;
    }
  }
}

PeopleDetector::~PeopleDetector() = default;
PeopleDetector::PeopleDetector(PeopleDetector&&) noexcept = default;
PeopleDetector& PeopleDetector::operator=(PeopleDetector&&) noexcept = default;

std::vector<PersonBox> PeopleDetector::detect(const cv::Mat& picture, const CameraPose* cam) {
  if (picture.empty()) return {};
  if (picture.type() == CV_8UC3)
    cv::cvtColor(picture, impl_->grey, cv::COLOR_BGR2GRAY);
  else if (picture.type() == CV_8UC1)
    impl_->grey = picture;
  else
    throw std::invalid_argument("people detector: picture type " + std::to_string(picture.type()) +
                                " is neither CV_8UC3 nor CV_8UC1");
  const double up = options_.upscale;
  const cv::Mat* in = &impl_->grey;
  if (up > 1.0) {
    cv::resize(impl_->grey, impl_->scaled, cv::Size(), up, up, cv::INTER_LINEAR);
    in = &impl_->scaled;
  }
  const cv::Rect frame(0, 0, picture.cols, picture.rows);
  std::vector<PersonBox> out;
  if (isHog(options_.method)) {
    std::vector<cv::Rect> found;
    std::vector<double> weights;
    const cv::Size stride(options_.stride_px, options_.stride_px);
    if (options_.floor_band && cam) {
      CameraPose pose = *cam;  // the picture's own size (the focal length follows from it)
      pose.width = picture.cols;
      pose.height = picture.rows;
      floorBandHog(impl_->hog, *in, up, pose, options_, found, weights, impl_->level);
    } else {
      impl_->hog.detectMultiScale(*in, found, weights, options_.hit_threshold, stride, cv::Size(0, 0),
                                  options_.scale_step, static_cast<double>(options_.group_threshold));
    }
    for (std::size_t i = 0; i < found.size(); ++i) {
      const cv::Rect2d r(found[i].x / up, found[i].y / up, found[i].width / up, found[i].height / up);
      const cv::Rect box = trimWindow(r) & frame;
      if (!box.empty()) out.push_back({box, i < weights.size() ? weights[i] : 0.0, false});
    }
  } else {
    std::vector<cv::Rect> found;
    std::vector<int> neighbours;
    const bool upper = options_.method == DetectorMethod::HaarUpperBody;
    impl_->cascade.detectMultiScale(*in, found, neighbours, options_.scale_step, options_.group_threshold, 0,
                                    upper ? cv::Size(22, 18) : cv::Size(14, 28));
    for (std::size_t i = 0; i < found.size(); ++i) {
      const cv::Rect box = cv::Rect(static_cast<int>(std::lround(found[i].x / up)), static_cast<int>(std::lround(found[i].y / up)),
                                    static_cast<int>(std::lround(found[i].width / up)),
                                    static_cast<int>(std::lround(found[i].height / up))) & frame;
      if (!box.empty()) out.push_back({box, i < neighbours.size() ? static_cast<double>(neighbours[i]) : 0.0, upper});
    }
  }
  return out;
}

}  // namespace inspect::perception
