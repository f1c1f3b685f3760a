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
    std::snprintf(buf, sizeof buf, "%s x%.3g step %.3g stride %d thr %.2f group %d", std::string(methodName(o.method)).c_str(),
                  o.upscale, o.scale_step, o.stride_px, o.hit_threshold, o.group_threshold);
  else
    std::snprintf(buf, sizeof buf, "%s x%.3g step %.3g neighbours %d", std::string(methodName(o.method)).c_str(), o.upscale,
                  o.scale_step, o.group_threshold);
  return buf;
}

struct PeopleDetector::Impl {
  cv::HOGDescriptor hog;
  cv::CascadeClassifier cascade;
  cv::Mat grey, scaled;
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

std::vector<PersonBox> PeopleDetector::detect(const cv::Mat& picture) {
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
    impl_->hog.detectMultiScale(*in, found, weights, options_.hit_threshold, stride, cv::Size(0, 0), options_.scale_step,
                                static_cast<double>(options_.group_threshold));
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
