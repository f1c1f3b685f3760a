#pragma once
// How a simulated person looks to the camera (docs/simulator.md "Camera"):
// a look per person - height, build, clothes, skin and hair - drawn from a
// seed and the person's index, and their figure in the picture for the angle
// they are seen at (front, side, back) and the phase of their gait (legs and
// arms swinging with their speed).
//
// Proportions are fractions of the height (Drillis and Contini's segment
// lengths, as in Winter, "Biomechanics and Motor Control of Human Movement",
// Fig. 4.1): hip 0.53, knee 0.285, shoulder 0.818, chin 0.87; shoulders
// 0.259 wide, hips 0.191; upper arm 0.186, forearm 0.146, foot 0.152 long.
// Gait: the thighs swing +-25 degrees at a brisk walk, the knee of the leg
// in swing bends up to 60 degrees, the arms swing against the legs.
//
// Weak perspective: one person is drawn at the depth of their body axis (the
// few centimetres that a limb lies nearer or further do not change its size
// at the distances the camera sees people). Pure functions.
#include <cstdint>

#include <opencv2/core.hpp>

namespace inspect::sim {

/// What a person looks like; personLook() draws one per index from a seed.
struct PersonLook {
  double height_m = 1.75;
  double build = 1.0;  // widths scale: 0.85 slim .. 1.2 broad
  cv::Vec3f shirt{20, 120, 250};  // BGR, before shading
  cv::Vec3f trousers{70, 50, 36};
  cv::Vec3f skin{130, 165, 215};
  cv::Vec3f hair{28, 34, 44};
  cv::Vec3f shoes{30, 30, 34};
  bool short_sleeves = false;
};

/// The look of person `index` in a world drawn with `seed`: heights 1.75 +-
/// 0.09 m (1.50-1.98), builds, shirts from a dozen colours (greys and whites
/// that sink into a wall among them), trousers, skin and hair. The same
/// (seed, index) always gives the same look.
PersonLook personLook(uint32_t seed, int index);

/// How the person stands to the camera.
struct FigurePose {
  // Angle from the direction towards the camera to the person's facing,
  // turning towards the picture's right: 0 faces the camera, +-pi shows
  // the back, +pi/2 walks to the picture's right.
  double view_rad = 0.0;
  double gait_phase_rad = 0.0;  // 0..2 pi per stride (two steps)
  double stride = 0.0;          // 0 standing still .. 1 a brisk walk (swing amplitude)
};

/// The pose of someone seen at `view_rad` walking at `speed_m_s` who has
/// walked `walked_m` so far: one gait cycle (two steps) per 0.83 x height
/// walked, and a swing that grows with speed to 1 at 1.4 m/s.
FigurePose gaitAt(double view_rad, double speed_m_s, double walked_m, double height_m);

/// Where a person stands in the picture: the column of the body's vertical
/// axis, pixels per metre at their depth, and the row of a height.
struct FigurePlacement {
  double axis_col = 0.0;    // picture column of the body axis
  double horizon_row = 0.0; // row of the lens's height, far away
  double lens_z_m = 0.0;    // the lens above the floor
  double px_per_m = 1.0;    // focal length / depth
  double row(double z_m) const { return horizon_row + px_per_m * (lens_z_m - z_m); }
};

/// The figure's extent in picture coordinates (unclipped).
cv::Rect2d figureBounds(const PersonLook& look, const FigurePose& pose, const FigurePlacement& at);

/// Draws the figure into `colour` (CV_8UC3) and `mask` (CV_8UC1, 255 where
/// the figure is), two patches of the same size whose pixel (0, 0) is the
/// picture's pixel `origin`; what falls outside the patches is cut. Every
/// colour is scaled by `light` (the brightness at the person's distance).
void drawFigure(const PersonLook& look, const FigurePose& pose, const FigurePlacement& at, double light,
                cv::Point origin, cv::Mat& colour, cv::Mat& mask);

}  // namespace inspect::sim
