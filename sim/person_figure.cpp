#include "sim/person_figure.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace inspect::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kShift = 4;  // sub-pixel bits of OpenCV's drawing
constexpr double kSub = 1 << kShift;

// Clothes and people (BGR). Greys and white sink into the walls and floor:
// the detector has to meet them.
const cv::Vec3f kShirts[] = {{20, 120, 250}, {190, 96, 40}, {60, 150, 60},   {50, 50, 190},
                             {150, 70, 130}, {40, 170, 190}, {200, 200, 200}, {128, 128, 128},
                             {40, 40, 44},   {235, 235, 232}, {110, 60, 30},  {70, 110, 150}};
const cv::Vec3f kTrousers[] = {{70, 50, 36}, {52, 52, 56}, {60, 80, 96}, {110, 90, 70}, {95, 135, 160}, {30, 30, 32}};
const cv::Vec3f kSkins[] = {{130, 165, 215}, {110, 150, 200}, {96, 128, 178}, {70, 96, 140}, {50, 70, 100}};
const cv::Vec3f kHairs[] = {{28, 34, 44}, {30, 60, 100}, {90, 150, 190}, {150, 150, 155}, {20, 20, 24}};
const cv::Vec3f kShoes[] = {{30, 30, 34}, {200, 200, 205}, {40, 60, 90}};

// splitmix64: a well-mixed 64-bit hash, one draw per call.
uint64_t mix(uint64_t& s) {
  uint64_t z = (s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
double unit(uint64_t& s) { return static_cast<double>(mix(s) >> 11) * (1.0 / 9007199254740992.0); }
template <class T, std::size_t N>
const T& draw(const T (&table)[N], uint64_t& s) {
  return table[mix(s) % N];
}

// The figure as body points: a forward, b to the person's left, z up (m).
struct P3 {
  double a, b, z;
};

// Joints of one figure, with the body dropped so that the lower foot stands
// on the floor (the hip falls as the legs spread).
struct Skeleton {
  double H, w;  // height, build
  std::array<P3, 2> hip, knee, ankle, heel, toe;   // [0] left, [1] right
  std::array<P3, 2> shoulder, elbow, wrist, hand;
  double drop = 0;  // how far the body is lowered (m)
};

Skeleton skeleton(const PersonLook& look, const FigurePose& pose) {
  Skeleton k;
  const double H = look.height_m, w = look.build;
  k.H = H;
  k.w = w;
  const double s = std::clamp(pose.stride, 0.0, 1.0);
  const double A = 0.44 * s;  // thigh swing (rad), +-25 degrees at a brisk walk
  const double sp = std::sin(pose.gait_phase_rad), cp = std::cos(pose.gait_phase_rad);
  const double thigh = 0.245 * H, shin = 0.246 * H, ankle_h = 0.039 * H;
  const double upper = 0.186 * H, fore = 0.146 * H;
  for (int i = 0; i < 2; ++i) {
    const double side = i == 0 ? 1.0 : -1.0;                  // left +b
    const double theta = side * A * sp;                       // thigh, forward +
    const double kappa = 1.05 * s * std::max(0.0, side * cp);  // knee of the leg in swing
    k.hip[i] = {0, side * 0.052 * H * w, 0.53 * H};
    k.knee[i] = {k.hip[i].a + thigh * std::sin(theta), k.hip[i].b, k.hip[i].z - thigh * std::cos(theta)};
    k.ankle[i] = {k.knee[i].a + shin * std::sin(theta - kappa), k.hip[i].b, k.knee[i].z - shin * std::cos(theta - kappa)};
    // The shoe's sole on the floor under a level foot: its centre line half its thickness up.
    k.heel[i] = {k.ankle[i].a - 0.035 * H, k.hip[i].b, k.ankle[i].z - ankle_h + 0.025 * H};
    k.toe[i] = {k.ankle[i].a + 0.11 * H, k.hip[i].b, k.ankle[i].z - ankle_h + 0.0225 * H};
    // Arms swing against the leg of their side; the elbow bends a little more in a walk.
    const double psi = -side * 0.8 * A * sp, beta = 0.07, eps = 0.12 + 0.3 * s;
    k.shoulder[i] = {0, side * 0.116 * w * H, 0.80 * H};
    k.elbow[i] = {k.shoulder[i].a + upper * std::sin(psi), k.shoulder[i].b + side * upper * std::sin(beta),
                  k.shoulder[i].z - upper * std::cos(psi)};
    k.wrist[i] = {k.elbow[i].a + fore * std::sin(psi + eps), k.elbow[i].b + side * fore * std::sin(beta * 0.5),
                  k.elbow[i].z - fore * std::cos(psi + eps)};
    k.hand[i] = {k.wrist[i].a + 0.06 * H * std::sin(psi + eps), k.wrist[i].b, k.wrist[i].z - 0.06 * H * std::cos(psi + eps)};
  }
  k.drop = std::min(k.ankle[0].z, k.ankle[1].z) - ankle_h;
  return k;
}

// Projects body points into the patch.
struct Projector {
  double sa, ca;  // sin and cos of the view angle
  FigurePlacement at;
  double drop;
  cv::Point2d origin;
  cv::Point2d operator()(const P3& p) const {
    const double u = p.a * sa + p.b * ca;  // metres to the picture's right
    return {at.axis_col + at.px_per_m * u - origin.x, at.row(p.z - drop) - origin.y};
  }
  // Depth towards the camera (larger: nearer).
  double nearness(const P3& p) const { return p.a * ca - p.b * sa; }
};

cv::Point fixed(cv::Point2d p) {
  return {static_cast<int>(std::lround(p.x * kSub)), static_cast<int>(std::lround(p.y * kSub))};
}

cv::Scalar toScalar(const cv::Vec3f& c, double k) {
  return cv::Scalar(std::clamp(c[0] * k, 0.0, 255.0), std::clamp(c[1] * k, 0.0, 255.0), std::clamp(c[2] * k, 0.0, 255.0));
}

struct Painter {
  cv::Mat& colour;
  cv::Mat& mask;
  double px_per_m;
  // A limb: a tapering quadrilateral from p0 (width w0 m) to p1 (w1), round at both ends.
  void limb(cv::Point2d p0, cv::Point2d p1, double w0, double w1, const cv::Scalar& c) const {
    const double r0 = 0.5 * w0 * px_per_m, r1 = 0.5 * w1 * px_per_m;
    cv::Point2d d = p1 - p0;
    const double len = std::hypot(d.x, d.y);
    if (len > 1e-9) {
      const cv::Point2d n(-d.y / len, d.x / len);
      const std::array<cv::Point, 4> q{fixed(p0 + n * r0), fixed(p1 + n * r1), fixed(p1 - n * r1), fixed(p0 - n * r0)};
      cv::fillConvexPoly(colour, q.data(), 4, c, cv::LINE_8, kShift);
      cv::fillConvexPoly(mask, q.data(), 4, cv::Scalar(255), cv::LINE_8, kShift);
    }
    disc(p0, r0, c);
    disc(p1, r1, c);
  }
  void disc(cv::Point2d p, double r, const cv::Scalar& c) const {
    const int ri = static_cast<int>(std::lround(r * kSub));
    if (ri <= 0) return;
    cv::circle(colour, fixed(p), ri, c, cv::FILLED, cv::LINE_8, kShift);
    cv::circle(mask, fixed(p), ri, cv::Scalar(255), cv::FILLED, cv::LINE_8, kShift);
  }
  void ellipse(cv::Point2d centre, double ax_px, double ay_px, const cv::Scalar& c) const {
    const cv::Size axes(static_cast<int>(std::lround(ax_px * kSub)), static_cast<int>(std::lround(ay_px * kSub)));
    if (axes.width <= 0 || axes.height <= 0) return;
    cv::ellipse(colour, fixed(centre), axes, 0, 0, 360, c, cv::FILLED, cv::LINE_8, kShift);
    cv::ellipse(mask, fixed(centre), axes, 0, 0, 360, cv::Scalar(255), cv::FILLED, cv::LINE_8, kShift);
  }
  void polygon(const std::vector<cv::Point>& pts, const cv::Scalar& c) const {
    const cv::Point* p = pts.data();
    const int n = static_cast<int>(pts.size());
    cv::fillPoly(colour, &p, &n, 1, c, cv::LINE_8, kShift);
    cv::fillPoly(mask, &p, &n, 1, cv::Scalar(255), cv::LINE_8, kShift);
  }
};

}  // namespace

PersonLook personLook(uint32_t seed, int index) {
  uint64_t s = (static_cast<uint64_t>(seed) << 32) ^ static_cast<uint64_t>(static_cast<uint32_t>(index)) ^ 0x5EED0F0A11ull;
  mix(s);
  PersonLook l;
  // Height: about normal (sum of three uniforms), 1.75 +- 0.09 m.
  const double g = (unit(s) + unit(s) + unit(s) - 1.5) * 2.0;  // mean 0, sd 1
  l.height_m = std::clamp(1.75 + 0.09 * g, 1.50, 1.98);
  l.build = 0.85 + 0.35 * unit(s);
  l.shirt = draw(kShirts, s);
  l.trousers = draw(kTrousers, s);
  l.skin = draw(kSkins, s);
  l.hair = draw(kHairs, s);
  l.shoes = draw(kShoes, s);
  l.short_sleeves = unit(s) < 0.4;
  return l;
}

FigurePose gaitAt(double view_rad, double speed_m_s, double walked_m, double height_m) {
  FigurePose p;
  p.view_rad = view_rad;
  p.stride = std::clamp(speed_m_s / 1.4, 0.0, 1.0);
  const double cycle_m = 0.83 * std::max(0.5, height_m);
  p.gait_phase_rad = 2 * kPi * std::fmod(std::max(0.0, walked_m) / cycle_m, 1.0);
  return p;
}

cv::Rect2d figureBounds(const PersonLook& look, const FigurePose& pose, const FigurePlacement& at) {
  const Skeleton k = skeleton(look, pose);
  const Projector pr{std::sin(pose.view_rad), std::cos(pose.view_rad), at, k.drop, {0, 0}};
  double x0 = at.axis_col, x1 = at.axis_col;
  for (const auto* set : {&k.hip, &k.knee, &k.ankle, &k.heel, &k.toe, &k.shoulder, &k.elbow, &k.wrist, &k.hand})
    for (const auto& p : *set) {
      const double x = pr(p).x;
      x0 = std::min(x0, x);
      x1 = std::max(x1, x);
    }
  // Widths beyond the joints: the torso's half width, a limb's.
  const double margin = at.px_per_m * 0.2 * look.height_m * look.build;
  const double top = at.row(look.height_m - k.drop) - 2, bottom = at.row(-0.002 * look.height_m) + 2;
  return {x0 - margin, top, (x1 - x0) + 2 * margin, bottom - top};
}

void drawFigure(const PersonLook& look, const FigurePose& pose, const FigurePlacement& at, double light,
                cv::Point origin, cv::Mat& colour, cv::Mat& mask) {
  const Skeleton k = skeleton(look, pose);
  const double sa = std::sin(pose.view_rad), ca = std::cos(pose.view_rad);
  const Projector pr{sa, ca, at, k.drop, cv::Point2d(origin)};
  const Painter pt{colour, mask, at.px_per_m};
  const double H = k.H, w = k.w;

  // The left side (b > 0) is the far one when the person shows their right (sin > 0).
  const int far = pr.nearness(k.hip[0]) < pr.nearness(k.hip[1]) ? 0 : 1;
  const double kFar = 0.78, kNear = 0.96;
  auto leg = [&](int i, double shade) {
    const cv::Scalar tr = toScalar(look.trousers, light * shade);
    pt.limb(pr(k.hip[i]), pr(k.knee[i]), 0.085 * H * w, 0.058 * H * w, tr);
    pt.limb(pr(k.knee[i]), pr(k.ankle[i]), 0.058 * H * w, 0.042 * H * w, tr);
    pt.limb(pr(k.heel[i]), pr(k.toe[i]), 0.05 * H, 0.045 * H, toScalar(look.shoes, light * shade));
  };
  auto arm = [&](int i, double shade) {
    const cv::Scalar sleeve = toScalar(look.shirt, light * shade);
    const cv::Scalar skin = toScalar(look.skin, light * shade);
    pt.limb(pr(k.shoulder[i]), pr(k.elbow[i]), 0.058 * H * w, 0.047 * H * w, sleeve);
    pt.limb(pr(k.elbow[i]), pr(k.wrist[i]), 0.047 * H * w, 0.036 * H * w, look.short_sleeves ? skin : sleeve);
    pt.limb(pr(k.wrist[i]), pr(k.hand[i]), 0.036 * H, 0.03 * H, skin);
  };
  arm(far, kFar);
  leg(far, kFar);

  // Torso: a box whose silhouette is w|cos| + d|sin| wide at each height.
  struct Level {
    double z, half_w, half_d;
  };
  const double ac = std::abs(ca), as = std::abs(sa);
  // The chest is narrower than the shoulders: the arms' tops (deltoids) make their width.
  const std::array<Level, 6> torso{{{0.84 * H, 0.06 * H * w, 0.045 * H * w},
                                    {0.815 * H, 0.104 * H * w, 0.06 * H * w},
                                    {0.74 * H, 0.094 * H * w, 0.068 * H * w},
                                    {0.62 * H, 0.084 * H * w, 0.062 * H * w},
                                    {0.57 * H, 0.094 * H * w, 0.066 * H * w},
                                    {0.47 * H, 0.095 * H * w, 0.064 * H * w}}};
  auto half = [&](const Level& l) { return l.half_w * ac + l.half_d * as; };
  auto outline = [&](std::size_t from, std::size_t to) {  // levels [from, to]
    std::vector<cv::Point> pts;
    for (std::size_t i = from; i <= to; ++i) {
      const cv::Point2d c = pr({0, 0, torso[i].z});
      pts.push_back(fixed({c.x - half(torso[i]) * at.px_per_m, c.y}));
    }
    for (std::size_t i = to + 1; i-- > from;) {
      const cv::Point2d c = pr({0, 0, torso[i].z});
      pts.push_back(fixed({c.x + half(torso[i]) * at.px_per_m, c.y}));
    }
    return pts;
  };
  pt.polygon(outline(4, 5), toScalar(look.trousers, light));
  pt.polygon(outline(0, 4), toScalar(look.shirt, light));
  // Neck and head: hair all round, the face towards where they look.
  const cv::Scalar skin = toScalar(look.skin, light);
  pt.limb(pr({0, 0, 0.83 * H}), pr({0, 0, 0.875 * H}), 0.05 * H, 0.045 * H, toScalar(look.skin, light * 0.85));
  const double head_ax = (0.045 * ac + 0.056 * as) * H * at.px_per_m;
  pt.ellipse(pr({0, 0, 0.936 * H}), head_ax, 0.066 * H * at.px_per_m, toScalar(look.hair, light));
  if (ca > -0.25) {
    const double face_ax = 0.037 * H * (0.35 + 0.65 * std::max(0.0, ca)) * at.px_per_m;
    const cv::Point2d c = pr({0.02 * H, 0, 0.922 * H});  // the face lies forward of the axis
    pt.ellipse(c, face_ax, 0.05 * H * at.px_per_m, skin);
  }
  leg(1 - far, kNear);
  arm(1 - far, kNear);
}

}  // namespace inspect::sim
