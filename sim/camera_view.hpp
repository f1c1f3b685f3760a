#pragma once
// What the robot's PTZ camera sees in the simulated world, drawn as a BGR
// picture: walls and obstacle faces (shaded by distance and by the angle they
// are seen at), a tiled floor with the world's floor lines on it, a ceiling,
// the pedestrians as figures seen from the front, side or back with their
// gait, heights and clothes (sim/person_figure.hpp), optionally sensor noise
// and motion blur, and along the top the machine-readable
// time code of shared/video/timecode.hpp with the frame counter and time as
// text at the bottom (docs/simulator.md "Camera").
//
// A column renderer: every picture column is one horizontal ray from the lens
// (pinhole, square pixels, `hfov_deg` across), cast against every wall and
// obstacle edge; the hits are painted nearest first, each as the vertical
// span that its height covers at its distance, so obstacles lower than the
// lens show their tops and what lies behind them. Walls are
// `wall_height_m` tall and meet a flat ceiling, obstacles `obstacle_height_m`
// (the world file gives no heights). Tilt moves the horizon (vertical edges
// stay vertical: exact at tilt 0, a y-shear approximation otherwise).
// Pure: no clock, no I/O; the scene is an argument. Not thread-safe (one
// thread renders with one CameraView).
#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "shared/config/robot_config.hpp"
#include "shared/control/diff_drive.hpp"
#include "sim/world_names.hpp"

namespace inspect::sim {

/// A person as the camera sees them.
struct PersonInView {
  Vec2 position;           // centre of the body circle, world frame (m)
  double radius_m = 0.25;  // body circle (the world file's radius_m)
  int index = 0;           // the world file's pedestrian index (picks their look)
  double heading_rad = 0;  // where they face, world frame
  double speed_m_s = 0;    // how fast they walk (the swing of the gait)
  double walked_m = 0;     // how far they have walked (the phase of the gait)
};

/// Where a person was drawn, from the camera model: the truth that a
/// detector's boxes are scored against (experiments/bench/bench_people).
struct PersonTruth {
  int index = 0;             // PersonInView::index
  cv::Rect box;              // the whole figure's box, cut to the picture (empty when out of it)
  cv::Rect2d full_box;       // the same, not cut
  double distance_m = 0;     // lens to the body axis, on the floor
  double bearing_rad = 0;    // of the body axis from the optical axis, left positive
  double view_rad = 0;       // FigurePose::view_rad: 0 faces the camera, pi the back
  double visible = 0;        // share of the figure's pixels shown (walls, boxes, people and the picture's edge hide the rest)
  bool feet_in_view = false; // the lower foot's row is inside the picture
  bool head_in_view = false; // the top of the head is inside the picture
};

class PedestrianCrowd;
/// Replaces `out` with the crowd's present pedestrians as the camera draws
/// them (body, look index, facing, speed, walked distance). No allocation
/// once `out` has the capacity.
void peopleInView(const PedestrianCrowd& crowd, std::vector<PersonInView>& out);

/// One instant of the world's truth, as the camera shows it.
struct CameraScene {
  control::Pose2 robot;              // true pose of the axle midpoint
  double pan_rad = 0.0;              // PTZ set-point, counter-clockwise positive
  double tilt_rad = 0.0;             // up positive; clamped to +-80 degrees
  std::vector<PersonInView> people;  // the present pedestrians
  double sim_time_s = 0.0;           // shown in the caption
  double yaw_rate_rad_s = 0.0;       // the camera's turn rate (robot + pan): motion blur
};

/// What the world file does not say: heights, and how quickly light falls off.
struct CameraViewStyle {
  double wall_height_m = 2.6;      // walls reach the ceiling at this height
  double obstacle_height_m = 1.0;  // benches, boxes, shelves
  double falloff_m = 9.0;          // brightness 0.3 + 0.7 exp(-distance / falloff_m)
  uint32_t look_seed = 0;          // people's heights, builds and clothes (sim/person_figure.hpp)
  // A real sensor (0 = off, a clean synthetic picture): Gaussian noise of this
  // standard deviation in grey levels, and motion blur along the rows over
  // the exposure while the camera turns (yaw_rate_rad_s x exposure, in pixels).
  double noise_sigma = 0.0;
  double exposure_ms = 0.0;
};

class CameraView {
 public:
  /// Throws std::invalid_argument for a size below 64x64 or above 4096x4096.
  CameraView(const World& world, const config::CameraMount& mount, int width, int height,
             CameraViewStyle style = {});

  /// Draws the view of `scene` into `bgr` (made width x height, CV_8UC3), with
  /// the time code of (capture_us, frame_index) along the top.
  void render(const CameraScene& scene, uint64_t capture_us, uint32_t frame_index, cv::Mat& bgr);

  int width() const { return width_; }
  int height() const { return height_; }
  /// Focal length in pixels: (width / 2) / tan(hfov / 2).
  double focalPx() const { return f_; }
  /// The picture column (pixel centres at n + 0.5) at which a world point at
  /// any height appears; nullopt when it is not in front of the lens.
  std::optional<double> columnOf(const CameraScene& scene, Vec2 p) const;
  /// The row of the horizon (height of the lens, far away).
  double horizonRow(const CameraScene& scene) const;
  /// The people of the last render(), nearest last, each with where they
  /// were drawn and how much of them was shown (people behind the lens left out).
  const std::vector<PersonTruth>& peopleDrawn() const { return drawn_; }

 private:
  struct Face {  // one wall segment or obstacle edge
    Vec2 a, b;
    float height;
    int obstacle;  // index, -1 for a wall
    float light;   // lighting of its orientation (fixed light direction)
  };
  struct Hit {
    float depth;   // along the camera's axis (m)
    float along;   // distance from the face's first end (m)
    float facing;  // |cos| between the ray and the face's normal
    int face;
  };
  struct Lens {  // the camera's pose for one picture
    Vec2 c, fwd, left;
    double horizon;
  };
  Lens lens(const CameraScene& scene) const;
  void drawBackground(const Lens& l, cv::Mat& bgr) const;
  void drawFloorLines(const Lens& l, cv::Mat& bgr) const;
  void castColumns(const Lens& l);
  void paintColumns(const Lens& l, cv::Mat& bgr);
  void drawPeople(const CameraScene& scene, const Lens& l, cv::Mat& bgr);
  void drawCaption(const CameraScene& scene, uint64_t capture_us, uint32_t frame_index, cv::Mat& bgr) const;
  void applySensor(const CameraScene& scene, uint32_t frame_index, cv::Mat& bgr);
  double brightness(double distance_m) const;

  static constexpr int kMaxHits = 12;  // nearest hits kept per column

  int width_, height_;
  double f_, cx_, cy_;
  config::CameraMount mount_;
  CameraViewStyle style_;
  std::vector<Face> faces_;
  std::vector<std::array<Vec2, 4>> line_pieces_;  // floor lines cut into pieces <= 0.5 m
  std::vector<float> slope_;      // per column: (y / x) of its ray in the camera frame
  std::vector<float> ray_len_;    // per column: sqrt(1 + slope^2)
  std::vector<Hit> hits_;         // width x kMaxHits
  std::vector<int> hit_count_;    // per column
  std::vector<int> limit_;        // width x kMaxHits: top row painted once hit k is painted
  std::vector<int> painted_;      // per column: hits painted
  std::vector<PersonTruth> drawn_;
  cv::Mat owner_;                 // CV_16SC1: which drawn_ entry painted each pixel (-1: none)
  cv::Mat patch_, patch_mask_, count_mask_;  // one figure's drawing
  cv::Mat noise_;                 // CV_16SC3, 2x the picture: a window of it per picture
};

}  // namespace inspect::sim
