#include "pc_server/scene/camera_people.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "pc_server/scene/foxglove_fields.hpp"

namespace inspect::server::scene {

namespace {

void addPoint(::foxglove::PointsAnnotation* a, double x, double y) {
  auto* p = a->add_points();
  p->set_x(x);
  p->set_y(y);
}

std::string label(const v1::SeenPerson& s) {
  char buf[64];
  const double deg = s.bearing_rad() * 180 / std::numbers::pi;
  if (s.has_range_m())
    std::snprintf(buf, sizeof buf, "person %+.0f deg %.1f m", deg, s.range_m());
  else
    std::snprintf(buf, sizeof buf, "person %+.0f deg, feet not in view", deg);
  return buf;
}

}  // namespace

::foxglove::ImageAnnotations cameraPeople(const v1::Perception& p, uint32_t video_w, uint32_t video_h, uint64_t ns) {
  ::foxglove::ImageAnnotations a;
  setTime(a.mutable_timestamp(), ns);
  const double sx = p.width() && video_w ? static_cast<double>(video_w) / p.width() : 1.0;
  const double sy = p.height() && video_h ? static_cast<double>(video_h) / p.height() : 1.0;
  for (const auto& s : p.people()) {
    const double x0 = s.box_x() * sx, y0 = s.box_y() * sy;
    const double x1 = (s.box_x() + s.box_w()) * sx, y1 = (s.box_y() + s.box_h()) * sy;
    // Orange as the bearing rays of the 3-D scene; dimmer without a range.
    const double alpha = s.has_range_m() ? 1.0 : 0.6;
    auto* box = a.add_points();
    setTime(box->mutable_timestamp(), ns);
    box->set_type(::foxglove::PointsAnnotation::LINE_LOOP);
    addPoint(box, x0, y0);
    addPoint(box, x1, y0);
    addPoint(box, x1, y1);
    addPoint(box, x0, y1);
    setColor(box->mutable_outline_color(), 1.0, 0.55, 0.1, alpha);
    box->set_thickness(2);
    auto* text = a.add_texts();
    setTime(text->mutable_timestamp(), ns);
    text->mutable_position()->set_x(x0);
    text->mutable_position()->set_y(std::max(y0 - 2, 12.0));
    text->set_text(label(s));
    text->set_font_size(12);
    setColor(text->mutable_text_color(), 1, 1, 1, 1);
    setColor(text->mutable_background_color(), 1.0, 0.55, 0.1, 0.7 * alpha);
  }
  return a;
}

void CameraPeopleClock::onAccessUnit(const video::Frame& f, uint64_t capture_server_us, uint64_t ns) {
  if (!f.capture_us || !capture_server_us) return;
  video_offset_us_ = static_cast<int64_t>(capture_server_us - *f.capture_us);  // wraps as the receiver's sum
  pictures_[next_] = {*f.capture_us, ns};
  next_ = (next_ + 1) % kPictures;
}

std::optional<uint64_t> CameraPeopleClock::fresh(const v1::Perception& p, int64_t link_offset_us,
                                                 uint64_t (*to_wall_ns)(uint64_t)) {
  const uint64_t c = p.capture_us();
  if (c == 0 || c == last_capture_us_) return std::nullopt;
  last_capture_us_ = c;
  for (const auto& [robot_us, ns] : pictures_)
    if (robot_us == c && ns) return ns;
  return to_wall_ns(c + static_cast<uint64_t>(video_offset_us_.value_or(link_offset_us)));
}

}  // namespace inspect::server::scene
