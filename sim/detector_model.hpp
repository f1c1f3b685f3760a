#pragma once
// What the robot's camera people detector reports, without rendering a
// picture: the social arena's thousands of runs cannot afford rendering and
// HOG at 5 Hz (70 ms a picture), so they draw detections from this model,
// calibrated on bench_people's figures for the realistic renderer and the
// chosen detector (docs/human-awareness.md, "The arena's detector model").
//
// Per picture, for each person present: the share of their body the lens
// sees (7 rays across the body's width at the lens, against the walls, the
// obstacles, closer people and the picture's edges); found with the recall
// of their distance and share (bench_people's recall by distance for people
// 90-100 % visible and for those 30-90 % visible; nobody under 30 %); the
// bearing with Gaussian noise; the foot-row range with the bench's skewed
// error (long more often than short) when the feet are in the picture.
// False boxes: Poisson per picture, anywhere in the view at 3-8 m.
// Deterministic for a given random engine.
#include <array>
#include <random>
#include <vector>

#include "shared/behavior/camera_look.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/control/diff_drive.hpp"
#include "shared/world/world.hpp"

namespace inspect::sim {

struct DetectorModelParams {
  // Recall up to each distance from the lens (bench_people, 640x480 hog with
  // the floor band, seed 1, 300 pictures; 2026-12-07).
  std::array<double, 6> upto_m{2.0, 3.0, 4.0, 6.0, 8.0, 10.0};
  std::array<double, 6> recall_clear{0.0, 0.06, 0.42, 0.73, 0.79, 0.62};  // 90-100 % visible
  std::array<double, 6> recall_part{0.0, 0.0, 0.05, 0.06, 0.20, 0.0};     // 30-90 % visible
  double bearing_sigma_deg = 0.2;   // |error| p50 0.13, p90 0.35 deg: a normal's sigma 0.19-0.21
  // Foot-row range error (signed, share of the distance): median +10.6 %,
  // p10 -6.8 %, p90 +35.5 %: a two-piece normal about the median.
  double range_median = 0.106, range_sigma_short = 0.136, range_sigma_long = 0.194;
  double false_per_picture = 0.0033;  // 1 false box in 300 pictures (0.027 without the floor band)
  double false_min_m = 3.0, false_max_m = 8.0;
};

/// The wide head's model (robot config `wide_camera`, 120 degrees at 0.55 m):
/// bench_people --head wide, 480x360 hog with one window agreeing and the
/// floor band, seed 1, 300 pictures (docs/human-awareness.md "The wide
/// head"): recall 2/26, 24/48, 41/51, 51/83, 8/72, 2/79 of people 90-100 %
/// visible up to 1, 1.5, 2, 3, 4, 6 m (1/34, 1/19, 0/7, 6/19, 0/13, 0/18 of
/// those 30-90 %); bearing |error| p50 0.33, p90 0.96 deg; foot-row range
/// signed p10 / p50 / p90 -12.6 / +9.9 / +30.9 %; no false box in 300 pictures.
DetectorModelParams wideHeadModel();

/// One person as the model sees them: a disc on the floor.
struct PersonDisc {
  double x_m = 0, y_m = 0, radius_m = 0.25;
};

/// Share of a person's body in view from `lens` (odometry = world frame), 0-1.
double visibleShare(const world::World& w, const control::Pose2& lens, double half_fov_rad, const PersonDisc& p,
                    const std::vector<PersonDisc>& others);

/// One picture's detections. `robot` the true pose, `pan_rad` the PTZ pan,
/// `people` every person present; the view's vertical extent from the
/// mount's height and tilt and the picture's 4:3 aspect decides whether the
/// feet are in the picture.
behavior::CameraLook detectPeople(const world::World& w, const control::Pose2& robot, const config::CameraMount& mount,
                                  double pan_rad, const std::vector<PersonDisc>& people,
                                  const DetectorModelParams& params, std::mt19937_64& rng);

}  // namespace inspect::sim
