#include "sim/camera_view.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "shared/video/timecode.hpp"
#include "sim/pedestrian_crowd.hpp"
#include "sim/person_figure.hpp"

namespace inspect::sim {

void peopleInView(const PedestrianCrowd& crowd, std::vector<PersonInView>& out) {
  out.clear();
  for (std::size_t i = 0; i < crowd.size(); ++i) {
    if (!crowd.present(i)) continue;
    const auto& a = crowd.agent(i);
    out.push_back({{a.position_m.x(), a.position_m.y()}, a.radius_m, static_cast<int>(i), crowd.facingRad(i),
                   a.velocity_m_s.norm(), crowd.walkedM(i)});
  }
}

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kNear_m = 0.05;               // nothing nearer the lens is drawn
constexpr double kTiltLimit_rad = 80.0 * kPi / 180.0;
constexpr double kTile_m = 0.6;                // floor tiles
constexpr double kGrout_m = 0.012;
constexpr double kPanel_m = 1.25;              // seams between wall panels
constexpr double kDoor_m = 0.6;                // ... and between an obstacle's cabinet doors
constexpr double kSeam_m = 0.012;
constexpr double kLightGrid_m = 2.4;           // ceiling light panels, one per cell of this grid
constexpr double kLightLong_m = 1.2;           // their size
constexpr double kLightShort_m = 0.3;
constexpr double kLinePiece_m = 0.5;           // floor lines are drawn in pieces this long
constexpr double kRowClamp = 1e6;              // rows beyond this are off the picture anyway

// Colours (BGR, 0-255 before shading).
const cv::Vec3f kCeiling(212, 212, 206);
const cv::Vec3f kFloor(116, 121, 124);
const cv::Vec3f kGrout(78, 80, 82);
const cv::Vec3f kWallUpper(184, 197, 205);
const cv::Vec3f kWallLower(140, 160, 152);
const cv::Vec3f kRail(62, 98, 136);
const cv::Vec3f kSkirting(58, 60, 64);
const cv::Vec3f kLineColour(24, 196, 232);  // yellow tape
const cv::Vec3f kObstacles[] = {{72, 112, 160}, {150, 118, 84}, {84, 140, 104}, {128, 92, 140}, {96, 150, 170}};

template <class T, std::size_t N>
const T& pick(const T (&table)[N], int i) {
  return table[static_cast<std::size_t>(i < 0 ? -i : i) % N];
}

cv::Vec3b shade(const cv::Vec3f& c, double k) {
  return cv::Vec3b(cv::saturate_cast<uint8_t>(c[0] * k), cv::saturate_cast<uint8_t>(c[1] * k),
                   cv::saturate_cast<uint8_t>(c[2] * k));
}

// The first pixel row whose centre lies at or below picture height y.
int toRow(double y) { return static_cast<int>(std::ceil(std::clamp(y, -kRowClamp, kRowClamp) - 0.5)); }

// Rows [r0, r1) of one column, clipped to the picture.
void paintSpan(cv::Mat& img, int col, int r0, int r1, cv::Vec3b c) {
  r0 = std::max(r0, 0);
  r1 = std::min(r1, img.rows);
  if (r0 >= r1) return;
  const std::size_t step = img.step;
  uint8_t* p = img.data + static_cast<std::size_t>(r0) * step + 3 * static_cast<std::size_t>(col);
  for (int r = r0; r < r1; ++r, p += step) {
    p[0] = c[0];
    p[1] = c[1];
    p[2] = c[2];
  }
}

// A world point in the camera's plane frame: x along the axis, y to the left.
struct CamPoint {
  double x, y;
};

}  // namespace

CameraView::CameraView(const World& world, const config::CameraMount& mount, int width, int height,
                       CameraViewStyle style)
    : width_(width), height_(height), mount_(mount), style_(style) {
  if (width < 64 || height < 64 || width > 4096 || height > 4096)
    throw std::invalid_argument("camera view: size " + std::to_string(width) + "x" + std::to_string(height) +
                                " outside [64, 4096]");
  if (!(style.noise_sigma >= 0 && style.noise_sigma <= 50))
    throw std::invalid_argument("camera view: noise_sigma " + std::to_string(style.noise_sigma) + " outside [0, 50]");
  if (!(style.exposure_ms >= 0 && style.exposure_ms <= 100))
    throw std::invalid_argument("camera view: exposure_ms " + std::to_string(style.exposure_ms) + " outside [0, 100]");
  f_ = (width / 2.0) / std::tan(mount.hfov_deg * kPi / 360.0);
  cx_ = width / 2.0;
  cy_ = height / 2.0;
  // A fixed light direction tells the faces of a box apart.
  const Vec2 light = normalized(Vec2{0.6, 0.8});
  auto addFace = [&](const Segment& s, double h, int obstacle) {
    const Vec2 d = normalized(s.b - s.a);
    const double facing_light = std::abs(cross(d, light));  // |normal . light|
    faces_.push_back({s.a, s.b, static_cast<float>(h), obstacle, static_cast<float>(0.82 + 0.18 * facing_light)});
  };
  for (const auto& w : world.walls) addFace(w, style_.wall_height_m, -1);
  for (std::size_t i = 0; i < world.obstacles.size(); ++i)
    for (const auto& e : geometry::edgesOf(world.obstacles[i].polygon))
      addFace(e, style_.obstacle_height_m, static_cast<int>(i));
  for (const auto& line : world.floor_lines) {
    const Vec2 d = line.centre.b - line.centre.a;
    const double len = norm(d);
    if (!(len > 0)) continue;
    const Vec2 u = (1.0 / len) * d;
    const Vec2 n = (line.width_m / 2) * Vec2{-u.y, u.x};
    const int pieces = std::max(1, static_cast<int>(std::ceil(len / kLinePiece_m)));
    for (int k = 0; k < pieces; ++k) {
      const Vec2 p0 = line.centre.a + (len * k / pieces) * u;
      const Vec2 p1 = line.centre.a + (len * (k + 1) / pieces) * u;
      line_pieces_.push_back({p0 + n, p1 + n, p1 - n, p0 - n});
    }
  }
  slope_.resize(static_cast<std::size_t>(width));
  ray_len_.resize(static_cast<std::size_t>(width));
  for (int c = 0; c < width; ++c) {
    const double s = (cx_ - (c + 0.5)) / f_;  // y / x of the ray through the column's centre
    slope_[static_cast<std::size_t>(c)] = static_cast<float>(s);
    ray_len_[static_cast<std::size_t>(c)] = static_cast<float>(std::sqrt(1 + s * s));
  }
  hits_.resize(static_cast<std::size_t>(width) * kMaxHits);
  limit_.resize(static_cast<std::size_t>(width) * kMaxHits);
  hit_count_.resize(static_cast<std::size_t>(width));
  painted_.resize(static_cast<std::size_t>(width));
}

double CameraView::brightness(double d) const { return 0.3 + 0.7 * std::exp(-d / style_.falloff_m); }

CameraView::Lens CameraView::lens(const CameraScene& scene) const {
  const auto& r = scene.robot;
  const double c = std::cos(r.theta_rad), s = std::sin(r.theta_rad);
  const Vec2 at{r.x_m + c * mount_.x_m - s * mount_.y_m, r.y_m + s * mount_.x_m + c * mount_.y_m};
  const double yaw = r.theta_rad + scene.pan_rad;
  const Vec2 fwd = geometry::unitAt(yaw);
  const double tilt = std::clamp(scene.tilt_rad + mount_.tilt_deg * kPi / 180.0, -kTiltLimit_rad, kTiltLimit_rad);
  return {at, fwd, {-fwd.y, fwd.x}, cy_ + f_ * std::tan(tilt)};
}

double CameraView::horizonRow(const CameraScene& scene) const { return lens(scene).horizon; }

std::optional<double> CameraView::columnOf(const CameraScene& scene, Vec2 p) const {
  const Lens l = lens(scene);
  const Vec2 d = p - l.c;
  const double x = dot(d, l.fwd), y = dot(d, l.left);
  if (x < kNear_m) return std::nullopt;
  return cx_ - f_ * y / x;
}

void CameraView::render(const CameraScene& scene, uint64_t capture_us, uint32_t frame_index, cv::Mat& bgr) {
  bgr.create(height_, width_, CV_8UC3);
  const Lens l = lens(scene);
  drawBackground(l, bgr);
  drawFloorLines(l, bgr);
  castColumns(l);
  paintColumns(l, bgr);
  drawPeople(scene, l, bgr);
  applySensor(scene, frame_index, bgr);
  drawCaption(scene, capture_us, frame_index, bgr);
  video::drawTimecode(bgr, capture_us, frame_index);
}

// Ceiling rows above the horizon (one colour per row: its distance), the
// tiled floor below it (per pixel, stepping along the row in fixed point).
void CameraView::drawBackground(const Lens& l, cv::Mat& bgr) const {
  const double zc = mount_.z_m;
  const double above = std::max(0.05, style_.wall_height_m - zc);  // lens to ceiling
  const int first_floor = std::clamp(toRow(l.horizon), 0, height_);
  // Ceiling: light panels on a square grid, stepped along each row like the
  // floor's tiles (below); far off they fade into the ceiling's mean colour.
  constexpr double kLightUnits = 65536.0 / kLightGrid_m;
  constexpr int64_t kLightOffset = int64_t{1} << 40;
  const int half_long = static_cast<int>(std::lround(kLightLong_m / kLightGrid_m * 128));
  const int half_short = static_cast<int>(std::lround(kLightShort_m / kLightGrid_m * 128));
  const double lit_share = kLightLong_m * kLightShort_m / (kLightGrid_m * kLightGrid_m);
  const cv::Vec3f lamp(250, 250, 246);
  for (int r = 0; r < first_floor; ++r) {
    const double d = f_ * above / std::max(1e-6, l.horizon - (r + 0.5));
    const double b = brightness(d);
    const double detail = std::clamp(2.0 - d / (0.05 * f_), 0.0, 1.0);  // a pixel under 5 cm: panels drawn
    const cv::Vec3f mean = kCeiling * (1 - lit_share) + lamp * lit_share;
    const cv::Vec3b plain = shade(mean * (1 - detail) + kCeiling * detail, b);
    auto* p = bgr.ptr<cv::Vec3b>(r);
    if (detail <= 0) {
      std::fill(p, p + width_, plain);
      continue;
    }
    const cv::Vec3b lit = shade(mean * (1 - detail) + lamp * detail, std::min(1.0, b * 1.25));
    const double lateral0 = d * (cx_ - 0.5) / f_;
    const Vec2 p0 = l.c + d * l.fwd + lateral0 * l.left;
    const Vec2 step = (-d / f_) * l.left;
    int64_t qx = static_cast<int64_t>(std::llround(p0.x * kLightUnits)) + kLightOffset;
    int64_t qy = static_cast<int64_t>(std::llround(p0.y * kLightUnits)) + kLightOffset;
    const int64_t dqx = std::llround(step.x * kLightUnits), dqy = std::llround(step.y * kLightUnits);
    for (int c = 0; c < width_; ++c, qx += dqx, qy += dqy) {
      const int fx = std::abs(static_cast<int>((qx >> 8) & 255) - 128), fy = std::abs(static_cast<int>((qy >> 8) & 255) - 128);
      p[c] = fx < half_long && fy < half_short ? lit : plain;
    }
  }
  // Tile coordinates in 1/65536 of a tile, so that stepping 4096 columns
  // drifts by less than a thousandth of a tile.
  constexpr double kUnits = 65536.0 / kTile_m;
  constexpr int64_t kOffset = int64_t{1} << 40;  // keeps the coordinates positive
  const int grout_units = static_cast<int>(std::lround(kGrout_m / kTile_m * 256));
  for (int r = first_floor; r < height_; ++r) {
    const double d = f_ * zc / std::max(1e-6, (r + 0.5) - l.horizon);  // along the axis
    const double b = brightness(d);
    // Tiles show their shade and grout while a pixel is smaller than the grout;
    // further off both fade into the floor's mean colour (no shimmer).
    const double detail = std::clamp(1.6 - d * 1.0 / (kGrout_m * f_), 0.0, 1.0);
    const cv::Vec3f mean = kFloor * (1.0 - kGrout_m * 2 / kTile_m) + kGrout * (kGrout_m * 2 / kTile_m);
    cv::Vec3b tone[8];
    for (int k = 0; k < 8; ++k) tone[k] = shade(mean * (1 - detail) + kFloor * detail, b * (1 + detail * 0.035 * (k - 3.5) / 3.5));
    const cv::Vec3b grout = shade(mean * (1 - detail) + kGrout * detail, b);
    const double lateral0 = d * (cx_ - 0.5) / f_;  // column 0's centre, to the left
    const Vec2 p0 = l.c + d * l.fwd + lateral0 * l.left;
    const Vec2 step = (-d / f_) * l.left;
    int64_t qx = static_cast<int64_t>(std::llround(p0.x * kUnits)) + kOffset;
    int64_t qy = static_cast<int64_t>(std::llround(p0.y * kUnits)) + kOffset;
    const int64_t dqx = std::llround(step.x * kUnits), dqy = std::llround(step.y * kUnits);
    auto* p = bgr.ptr<cv::Vec3b>(r);
    for (int c = 0; c < width_; ++c, qx += dqx, qy += dqy) {
      const int fx = static_cast<int>((qx >> 8) & 255), fy = static_cast<int>((qy >> 8) & 255);
      if (fx < grout_units || fy < grout_units) {
        p[c] = grout;
      } else {
        const auto tx = static_cast<uint32_t>(qx >> 16), ty = static_cast<uint32_t>(qy >> 16);
        p[c] = tone[((tx * 73856093u) ^ (ty * 19349663u)) >> 29];
      }
    }
  }
}

// Floor lines: each piece a quadrilateral on the floor, cut at the near
// plane and filled in projection (walls painted later hide what lies behind them).
void CameraView::drawFloorLines(const Lens& l, cv::Mat& bgr) const {
  const double zc = mount_.z_m;
  std::array<CamPoint, 4> in;
  std::array<CamPoint, 8> clipped;
  std::array<cv::Point, 8> pts;
  for (const auto& piece : line_pieces_) {
    bool any_front = false;
    for (int k = 0; k < 4; ++k) {
      const Vec2 d = piece[static_cast<std::size_t>(k)] - l.c;
      in[static_cast<std::size_t>(k)] = {dot(d, l.fwd), dot(d, l.left)};
      any_front = any_front || in[static_cast<std::size_t>(k)].x > kNear_m;
    }
    if (!any_front) continue;
    // Sutherland-Hodgman against x >= near.
    int n = 0;
    for (int k = 0; k < 4; ++k) {
      const CamPoint a = in[static_cast<std::size_t>(k)], b = in[static_cast<std::size_t>((k + 1) % 4)];
      const bool ain = a.x >= kNear_m, bin = b.x >= kNear_m;
      if (ain) clipped[static_cast<std::size_t>(n++)] = a;
      if (ain != bin) {
        const double t = (kNear_m - a.x) / (b.x - a.x);
        clipped[static_cast<std::size_t>(n++)] = {kNear_m, a.y + t * (b.y - a.y)};
      }
    }
    if (n < 3) continue;
    double umin = 1e18, umax = -1e18, dmid = 0;
    for (int k = 0; k < n; ++k) {
      const CamPoint q = clipped[static_cast<std::size_t>(k)];
      const double u = std::clamp(cx_ - f_ * q.y / q.x, -kRowClamp, kRowClamp);
      const double v = std::clamp(l.horizon + f_ * zc / q.x, -kRowClamp, kRowClamp);
      umin = std::min(umin, u);
      umax = std::max(umax, u);
      dmid += std::hypot(q.x, q.y) / n;
      pts[static_cast<std::size_t>(k)] = cv::Point(static_cast<int>(std::lround(u * 16)), static_cast<int>(std::lround(v * 16)));
    }
    if (umax < 0 || umin > width_) continue;
    const cv::Vec3b c = shade(kLineColour, brightness(dmid));
    cv::fillConvexPoly(bgr, pts.data(), n, cv::Scalar(c[0], c[1], c[2]), cv::LINE_8, 4);
  }
}

// Every face against the rays of the columns it spans; per column the
// nearest kMaxHits hits, sorted by depth.
void CameraView::castColumns(const Lens& l) {
  std::fill(hit_count_.begin(), hit_count_.end(), 0);
  for (std::size_t fi = 0; fi < faces_.size(); ++fi) {
    const Face& face = faces_[fi];
    const Vec2 da = face.a - l.c, db = face.b - l.c;
    CamPoint a{dot(da, l.fwd), dot(da, l.left)}, b{dot(db, l.fwd), dot(db, l.left)};
    const double full = norm(face.b - face.a);
    double along_a = 0, along_b = full;
    if (a.x < kNear_m && b.x < kNear_m) continue;
    if (a.x < kNear_m || b.x < kNear_m) {  // cut at the near plane
      const double t = (kNear_m - a.x) / (b.x - a.x);
      const CamPoint m{kNear_m, a.y + t * (b.y - a.y)};
      if (a.x < kNear_m) {
        a = m;
        along_a = t * full;
      } else {
        b = m;
        along_b = t * full;
      }
    }
    const double ua = cx_ - f_ * a.y / a.x, ub = cx_ - f_ * b.y / b.x;
    const int c0 = std::max(0, static_cast<int>(std::ceil(std::min(ua, ub) - 0.5)));
    const int c1 = std::min(width_ - 1, static_cast<int>(std::floor(std::max(ua, ub) - 0.5)));
    if (c0 > c1) continue;
    const double dx = b.x - a.x, dy = b.y - a.y;
    const double len = std::hypot(dx, dy);
    if (!(len > 1e-9)) continue;
    for (int col = c0; col <= c1; ++col) {
      const double s = slope_[static_cast<std::size_t>(col)];
      const double den = dy - s * dx;
      if (std::abs(den) < 1e-12) continue;
      double t = (s * a.x - a.y) / den;
      if (t < -1e-6 || t > 1 + 1e-6) continue;
      t = std::clamp(t, 0.0, 1.0);
      const double depth = a.x + t * dx;
      if (depth < kNear_m) continue;
      const Hit h{static_cast<float>(depth), static_cast<float>(along_a + t * (along_b - along_a)),
                  static_cast<float>(std::abs(den) / (len * ray_len_[static_cast<std::size_t>(col)])),
                  static_cast<int>(fi)};
      // Insert in depth order; the farthest falls off a full column.
      Hit* hs = &hits_[static_cast<std::size_t>(col) * kMaxHits];
      int& n = hit_count_[static_cast<std::size_t>(col)];
      int k;
      if (n < kMaxHits) {
        k = n++;
      } else {
        if (hs[kMaxHits - 1].depth <= h.depth) continue;
        k = kMaxHits - 1;
      }
      while (k > 0 && hs[k - 1].depth > h.depth) {
        hs[k] = hs[k - 1];
        --k;
      }
      hs[k] = h;
    }
  }
}

// Each column nearest hit first, from the bottom of the picture up: a hit
// paints the rows of its face that nothing nearer covers; an obstacle's far
// edge paints the rows of its top between the two edges (seen only when the
// obstacle is lower than the lens). Rows nothing covers keep the background.
void CameraView::paintColumns(const Lens& l, cv::Mat& bgr) {
  const double zc = mount_.z_m;
  auto rowAt = [&](double z, double depth) { return toRow(l.horizon + f_ * (zc - z) / depth); };
  for (int col = 0; col < width_; ++col) {
    const std::size_t base = static_cast<std::size_t>(col) * kMaxHits;
    const int n = hit_count_[static_cast<std::size_t>(col)];
    int cur = height_;  // rows [cur, height) are painted or nearer floor
    int inside[kMaxHits];
    int n_inside = 0;
    for (int k = 0; k < n; ++k) {
      const Hit& h = hits_[base + static_cast<std::size_t>(k)];
      const Face& face = faces_[static_cast<std::size_t>(h.face)];
      if (cur <= 0) {
        limit_[base + static_cast<std::size_t>(k)] = 0;
        continue;
      }
      const double d = h.depth;
      const double b = brightness(d * ray_len_[static_cast<std::size_t>(col)]);
      const int top = rowAt(face.height, d);
      if (face.obstacle >= 0) {
        int* it = std::find(inside, inside + n_inside, face.obstacle);
        if (it != inside + n_inside) {  // leaving the obstacle: its top, seen from above
          *it = inside[--n_inside];
          if (top < cur) {
            const cv::Vec3f c = pick(kObstacles, face.obstacle) * 1.12f + cv::Vec3f(18, 18, 18);
            paintSpan(bgr, col, top, cur, shade(c, b));
            cur = std::max(0, top);
          }
          limit_[base + static_cast<std::size_t>(k)] = cur;
          continue;
        }
        inside[n_inside++] = face.obstacle;
      }
      const int bottom = std::min(rowAt(0.0, d), cur);
      if (top < bottom) {
        const double k_light = b * (0.5 + 0.5 * h.facing) * face.light;
        // Seams (wall panels, cabinet doors) while a pixel is narrower than a seam.
        const double footprint = d * ray_len_[static_cast<std::size_t>(col)] / (f_ * std::max(0.2, double(h.facing)));
        const double period = face.obstacle < 0 ? kPanel_m : kDoor_m;
        const double along = h.along - period * std::floor(h.along / period);
        const double seam = footprint < kSeam_m && (along < kSeam_m / 2 || along > period - kSeam_m / 2) ? 0.78 : 1.0;
        if (face.obstacle < 0) {
          // A corridor wall: skirting, a lower band, a rail, the upper wall.
          const double zs[5] = {0.0, 0.10, 0.95, 1.0, face.height};
          const cv::Vec3f* colours[4] = {&kSkirting, &kWallLower, &kRail, &kWallUpper};
          int lower_row = bottom;
          for (int band = 0; band < 4 && lower_row > top; ++band) {
            const int upper_row = std::max(top, rowAt(zs[band + 1], d));
            paintSpan(bgr, col, upper_row, lower_row, shade(*colours[band], k_light * (band == 0 ? 1.0 : seam)));
            lower_row = std::min(lower_row, upper_row);
          }
        } else {
          // An obstacle: a dark plinth, its body (cabinet doors), a lighter top edge.
          const cv::Vec3f& c = pick(kObstacles, face.obstacle);
          const int plinth = std::max(top, rowAt(0.06, d));
          const int edge = std::min(bottom, std::max(top, rowAt(face.height - 0.03, d)));
          paintSpan(bgr, col, plinth, bottom, shade(c * 0.45f, k_light));
          paintSpan(bgr, col, edge, std::min(plinth, bottom), shade(c, k_light * seam));
          paintSpan(bgr, col, top, edge, shade(c * 1.15f + cv::Vec3f(20, 20, 20), k_light));
        }
        cur = std::min(cur, std::max(0, top));
      }
      limit_[base + static_cast<std::size_t>(k)] = cur;
    }
  }
}

// People: a body (shirt, trousers with the legs apart, the arms hanging at
// its sides) with rounded shoulders, a neck and a head with hair, shaded as a cylinder, farthest
// first; in each column only the rows above what nearer hits painted.
// People far to near, each drawn as a figure (sim/person_figure.hpp) into a
// patch and laid into the picture below whatever walls and boxes stand
// nearer in each column; a map of which person painted each pixel gives how
// much of each was shown.
void CameraView::drawPeople(const CameraScene& scene, const Lens& l, cv::Mat& bgr) {
  drawn_.clear();
  struct Seen {
    double x, y;
    const PersonInView* p;
  };
  std::vector<Seen> seen;
  seen.reserve(scene.people.size());
  for (const auto& p : scene.people) {
    const Vec2 d = p.position - l.c;
    const double x = dot(d, l.fwd);
    if (x > p.radius_m * 0.5 + kNear_m) seen.push_back({x, dot(d, l.left), &p});
  }
  if (seen.empty()) return;
  std::sort(seen.begin(), seen.end(), [](const Seen& a, const Seen& b) { return a.x > b.x; });
  owner_.create(height_, width_, CV_16SC1);
  owner_.setTo(cv::Scalar(-1));
  const cv::Rect frame(0, 0, width_, height_);
  std::vector<double> full_area;
  std::vector<int> lim(static_cast<std::size_t>(width_));
  for (const auto& s : seen) {
    const PersonLook look = personLook(style_.look_seed, s.p->index);
    const Vec2 to_cam = l.c - s.p->position;
    const Vec2 facing = geometry::unitAt(s.p->heading_rad);
    const double view = std::atan2(cross(to_cam, facing), dot(to_cam, facing));
    const FigurePose pose = gaitAt(view, s.p->speed_m_s, s.p->walked_m, look.height_m);
    const FigurePlacement at{cx_ - f_ * s.y / s.x, l.horizon, mount_.z_m, f_ / s.x};
    PersonTruth t;
    t.index = s.p->index;
    t.distance_m = std::hypot(s.x, s.y);
    t.bearing_rad = std::atan2(s.y, s.x);
    t.view_rad = view;
    t.feet_in_view = at.row(0.0) < height_ && at.row(0.0) >= 0;
    t.head_in_view = at.row(look.height_m) >= 0 && at.row(look.height_m) < height_;
    const cv::Rect2d bounds = figureBounds(look, pose, at);
    const double light = brightness(t.distance_m);
    // The whole figure's area and box, drawn small enough to be cheap (~200 rows).
    const double k = std::min(1.0, 200.0 / std::max(1.0, bounds.height));
    FigurePlacement small = at;
    small.axis_col = (at.axis_col - bounds.x) * k;
    small.horizon_row = (at.horizon_row - bounds.y) * k;
    small.px_per_m = at.px_per_m * k;
    const cv::Size small_size(static_cast<int>(std::ceil(bounds.width * k)) + 1,
                              static_cast<int>(std::ceil(bounds.height * k)) + 1);
    count_mask_.create(small_size, CV_8UC1);
    count_mask_.setTo(0);
    patch_.create(small_size, CV_8UC3);
    drawFigure(look, pose, small, light, {0, 0}, patch_, count_mask_);
    const cv::Rect figure_small = cv::boundingRect(count_mask_);
    full_area.push_back(cv::countNonZero(count_mask_) / (k * k));
    t.full_box = {bounds.x + figure_small.x / k, bounds.y + figure_small.y / k, figure_small.width / k,
                  figure_small.height / k};
    const cv::Rect clip = cv::Rect(static_cast<int>(std::floor(bounds.x)), static_cast<int>(std::floor(bounds.y)),
                                   static_cast<int>(std::ceil(bounds.width)) + 1,
                                   static_cast<int>(std::ceil(bounds.height)) + 1) & frame;
    const int slot = static_cast<int>(drawn_.size());
    drawn_.push_back(t);
    if (clip.empty()) continue;
    patch_.create(clip.size(), CV_8UC3);
    patch_mask_.create(clip.size(), CV_8UC1);
    patch_mask_.setTo(0);
    drawFigure(look, pose, at, light, clip.tl(), patch_, patch_mask_);
    const cv::Rect shape = cv::boundingRect(patch_mask_);
    if (!shape.empty()) drawn_.back().box = shape + clip.tl();
    // Rows that walls and boxes nearer than the body's front leave free, per column.
    const double front = s.x - 0.15;
    for (int col = clip.x; col < clip.x + clip.width; ++col) {
      const std::size_t base = static_cast<std::size_t>(col) * kMaxHits;
      int lm = height_;
      for (int h = 0; h < hit_count_[static_cast<std::size_t>(col)]; ++h) {
        if (hits_[base + static_cast<std::size_t>(h)].depth >= front) break;
        lm = limit_[base + static_cast<std::size_t>(h)];
      }
      lim[static_cast<std::size_t>(col)] = lm;
    }
    for (int r = 0; r < clip.height; ++r) {
      const int row = clip.y + r;
      const uint8_t* m = patch_mask_.ptr<uint8_t>(r);
      const cv::Vec3b* c = patch_.ptr<cv::Vec3b>(r);
      cv::Vec3b* out = bgr.ptr<cv::Vec3b>(row) + clip.x;
      int16_t* own = owner_.ptr<int16_t>(row) + clip.x;
      for (int q = 0; q < clip.width; ++q) {
        if (m[q] == 0 || row >= lim[static_cast<std::size_t>(clip.x + q)]) continue;
        out[q] = c[q];
        own[q] = static_cast<int16_t>(slot);
      }
    }
  }
  std::vector<double> shown(drawn_.size(), 0.0);
  for (int r = 0; r < height_; ++r) {
    const int16_t* own = owner_.ptr<int16_t>(r);
    for (int c = 0; c < width_; ++c)
      if (own[c] >= 0) shown[static_cast<std::size_t>(own[c])] += 1;
  }
  for (std::size_t i = 0; i < drawn_.size(); ++i)
    drawn_[i].visible = full_area[i] > 0 ? std::min(1.0, shown[i] / full_area[i]) : 0.0;
}

// A real sensor: motion blur along the rows over the exposure, then noise
// (a window of a fixed noise field, moved per picture: cheap and seeded).
void CameraView::applySensor(const CameraScene& scene, uint32_t frame_index, cv::Mat& bgr) {
  if (style_.exposure_ms > 0) {
    const double px = f_ * std::abs(scene.yaw_rate_rad_s) * style_.exposure_ms * 1e-3;
    const int k = std::min(width_ / 4, static_cast<int>(std::lround(px)));
    if (k >= 2) cv::blur(bgr, bgr, cv::Size(k, 1), cv::Point(-1, -1), cv::BORDER_REPLICATE);
  }
  if (style_.noise_sigma > 0) {
    if (noise_.empty()) {
      noise_.create(2 * height_, 2 * width_, CV_16SC3);
      cv::RNG rng(0x5EEDu ^ style_.look_seed);
      rng.fill(noise_, cv::RNG::NORMAL, 0, style_.noise_sigma);
    }
    const uint64_t h = (frame_index + 1ull) * 0x9E3779B97F4A7C15ull;
    const int ox = static_cast<int>((h >> 20) % static_cast<uint64_t>(width_));
    const int oy = static_cast<int>((h >> 42) % static_cast<uint64_t>(height_));
    cv::add(bgr, noise_(cv::Rect(ox, oy, width_, height_)), bgr, cv::noArray(), CV_8U);
  }
}

// Frame counter, capture time, sim time and the PTZ angles, bottom left.
void CameraView::drawCaption(const CameraScene& scene, uint64_t capture_us, uint32_t frame_index,
                             cv::Mat& bgr) const {
  const int unit = std::max(1, std::min(width_, height_) / 48);
  char line1[64], line2[96];
  std::snprintf(line1, sizeof line1, "%u  %.3f ms", frame_index, static_cast<double>(capture_us) / 1000.0);
  std::snprintf(line2, sizeof line2, "sim %.2f s  pan %+ld  tilt %+ld deg", scene.sim_time_s,
                std::lround(scene.pan_rad * 180.0 / kPi),
                std::lround(std::clamp(scene.tilt_rad, -kTiltLimit_rad, kTiltLimit_rad) * 180.0 / kPi));
  const double scale = unit / 20.0;
  const int thick = std::max(1, unit / 8);
  int baseline = 0;
  const cv::Size s1 = cv::getTextSize(line1, cv::FONT_HERSHEY_SIMPLEX, scale * 1.4, thick, &baseline);
  const cv::Size s2 = cv::getTextSize(line2, cv::FONT_HERSHEY_SIMPLEX, scale, thick, &baseline);
  const int pad = unit / 2 + 1;
  const int box_w = std::min(width_, std::max(s1.width, s2.width) + 2 * pad);
  const int box_h = std::min(height_, s1.height + s2.height + 4 * pad);
  cv::Mat box = bgr(cv::Rect(0, height_ - box_h, box_w, box_h));
  box.convertTo(box, -1, 0.4);
  cv::putText(bgr, line1, cv::Point(pad, height_ - box_h + pad + s1.height), cv::FONT_HERSHEY_SIMPLEX, scale * 1.4,
              cv::Scalar(255, 255, 255), thick, cv::LINE_8);
  cv::putText(bgr, line2, cv::Point(pad, height_ - pad - 1), cv::FONT_HERSHEY_SIMPLEX, scale,
              cv::Scalar(230, 230, 230), thick, cv::LINE_8);
}

}  // namespace inspect::sim
