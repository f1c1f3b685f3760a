#pragma once
// People from the 4 ultrasonic sensors alone (2 front, 1 left, 1 right).
//
// Each valid echo becomes a point in the odometry frame (beam centre at the
// measured range). Points near known static structure are dropped: the map
// (walls/obstacles given to the robot, optional) and a persistence grid
// (cells hit again and again over seconds while the robot moves are static).
// The remaining points are associated (nearest neighbour within a gate) with
// tracks, each a constant-velocity Kalman filter on (x, y, vx, vy) whose
// measurement covariance is elongated across the beam (a sonar knows range
// well, bearing only within its cone). Tracks are confirmed after a few hits
// and dropped after a coasting time; tracks that never move are reclassified
// as static. Deterministic; time enters as dt; no allocation per step.
//
// The camera (observeCamera, camera_fusion.cpp) adds bearings and foot-row
// ranges as measurements of the same filter (an extended Kalman update, the
// measurement being polar from the lens), starts tracks of its own, and keeps
// each track's log-odds of being a person: what the camera confirms is a
// person even standing still, what it looks at and never finds is not.
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "shared/behavior/camera_look.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/control/diff_drive.hpp"
#include "shared/geometry/segment.hpp"

namespace inspect::behavior {


struct HumanTrackerParams {
  double gate_m = 0.8;                // association gate (Euclidean, predicted position to point)
  double map_margin_m = 0.2;          // points this close to a map segment are static
  int confirm_hits = 3;               // hits needed to confirm a track
  double confirm_window_s = 1.0;      // ...within this time
  double coast_s = 1.5;               // drop a track not seen for this long
  double min_person_speed_m_s = 0.15; // slower confirmed tracks count as static objects after static_after_s
  double static_after_s = 3.0;
  double person_hold_s = 30.0;        // a person standing still stays a tracked person this long
  double moving_for_s = 0.3;          // ...and faster ones count as people after moving this long
  double process_accel_m_s2 = 1.0;    // white-acceleration process noise
  double range_sigma_m = 0.03;        // sonar range noise (paper +-0.03 m)
  double grid_cell_m = 0.2;           // persistence grid
  int grid_size = 200;                // cells per side (40 m x 40 m around the start)
  double grid_static_s = 1.5;         // a cell hit continuously for this long is static structure
  double grid_forget_s = 1.0;         // a cell not hit for this long starts afresh
  int max_tracks = 8;
  bool triangulate_front = true;      // fuse the two front echoes into one point when they agree
  double contradiction_margin_m = 0.4;  // a sensor hearing this much beyond a track's position contradicts it
  int contradiction_ticks = 3;        // ...on this many ticks in a row: the track is dropped
  // A side sensor sliding along a wall (no map needed): its echo points of the
  // last wall_trace_s lie on a line parallel to the robot's motion, spread as
  // far as the robot moved. Such echoes are structure (a person walking
  // alongside at the robot's speed looks the same: no pattern to react to).
  // New tracks start only from echoes this far inside the sonar's maximum
  // range: at its edge the cones' rims graze walls and openings (echoes that
  // slide with the robot), while the speed rule acts inside 3 m anyway.
  double new_track_margin_m = 0.3;
  bool wall_trace = true;
  double wall_trace_s = 0.5;
  double wall_trace_width_m = 0.03;   // the points' RMS distance from their line
  double wall_trace_angle_deg = 10;   // the line within this of the robot's heading
  CameraFusionParams camera;
};

/// One tracked object (odometry frame); a person once confirmed and moving.
struct HumanTrack {
  int id = 0;
  Eigen::Vector4d x = Eigen::Vector4d::Zero();   // x, y, vx, vy
  Eigen::Matrix4d p = Eigen::Matrix4d::Identity();
  double first_seen_s = 0, last_seen_s = 0;
  int hits = 0;
  bool confirmed = false;
  double slow_since_s = -1;    // time the track became slower than min_person_speed
  double moving_since_s = -1;  // time it became faster
  bool person = false;         // confirmed and moving for moving_for_s
  int contradicted = 0;        // ticks in a row a sensor looked through its position
  // The camera's evidence (camera_fusion.cpp).
  int camera_hits = 0;         // detections associated with this track
  double camera_seen_s = -1;   // time of the last one
  int camera_misses = 0;       // pictures in a row that should have shown it and did not
  double person_logodds = 0;   // camera evidence that this is a person (0 = none either way)
  bool camera_denied = false;  // person_logodds at or below the deny level: not a person
  bool camera_doubted = false; // never detected and person_logodds at or below the doubt level: not a person yet
  bool isPerson() const { return person && !camera_denied && !camera_doubted; }
  double speed() const { return std::hypot(x[2], x[3]); }
  double positionSigma() const { return std::sqrt(std::max(p(0, 0), p(1, 1))); }
};

/// One sonar's echo as a point in the odometry frame with its covariance
/// (HumanTracker::echoOf).
struct SonarEcho {
  bool use = false;
  Eigen::Vector2d z = Eigen::Vector2d::Zero();
  Eigen::Matrix2d r = Eigen::Matrix2d::Identity();
  double range = 0;
  double yaw = 0;  // the beam's direction (odometry frame)
};
using SonarEchoes = std::array<SonarEcho, 4>;

/// Detection bookkeeping (for telemetry and the scenario suite).
struct TrackerCounters {
  uint64_t echoes = 0;            // valid ranges seen
  uint64_t static_map = 0;        // dropped: near the map
  uint64_t static_grid = 0;       // dropped: persistent structure
  uint64_t associated = 0;        // joined an existing track
  uint64_t tracks_created = 0;
  uint64_t tracks_confirmed = 0;
  uint64_t tracks_unconfirmed_dropped = 0;  // likely false detections
  uint64_t tracks_static_dropped = 0;       // became static objects
  uint64_t triangulated = 0;                // front echo pairs fused into one point
  uint64_t static_wall_trace = 0;           // dropped: a side sensor sliding along a wall
  uint64_t static_learned = 0;              // dropped: on a wall learned that way (front cones' edges)
  uint64_t tracks_contradicted = 0;         // dropped: a sensor saw through them
  uint64_t camera_looks = 0;                // pictures taken in
  uint64_t camera_detections = 0;           // people in them
  uint64_t camera_associated = 0;           // ...that updated a track
  uint64_t camera_tracks_created = 0;       // ...that started one
  uint64_t camera_merged = 0;               // sonar tracks found to be a detected person's, merged into its track
  uint64_t camera_misses = 0;               // track-pictures that should have shown a track and did not
  uint64_t camera_denials = 0;              // tracks that became not-a-person by the camera
  uint64_t camera_echo_joins = 0;           // echoes beyond the gate put on a camera track within its range uncertainty
};

class HumanTracker {
 public:
  HumanTracker(const config::UltrasonicConfig& sonar, const HumanTrackerParams& params,
               std::vector<geometry::Segment> map = {});

  /// One tick: robot pose (odometry frame), the 4 ranges (< 0 = no echo), time.
  void step(const control::Pose2& pose, const std::array<double, 4>& ranges_m, double t_s);
  /// One camera picture's people, the robot at `pose` when it was taken,
  /// against the tracks as of the last step (nothing before the first step;
  /// the tracker's time is the steps' alone).
  void observeCamera(const control::Pose2& pose, const CameraLook& look);

  const std::vector<HumanTrack>& tracks() const { return tracks_; }
  const TrackerCounters& counters() const { return counters_; }
  /// The confirmed person nearest to `pose` (nullptr if none).
  const HumanTrack* nearest(const control::Pose2& pose) const;
  /// Per sensor, last step: its echo went to a track that is a person (such
  /// echoes are people, not obstacles to steer round: they get the Eq 9 factor).
  const std::array<bool, 4>& personEchoes() const { return person_echo_; }
  // The steps of step(), in its order; public so that each is tested on its
  // own (tests/shared/behavior/test_tracker_steps.cpp). step() predicts the
  // tracks to t_s first; the steps take the tracks as they are.

  /// 1. Sensor i's range as a point, or nothing when structure explains it:
  /// the map (any point of its arc within the cone), a wall the side sensors
  /// traced, a cell that keeps echoing (grid_static_s), or a side sensor's
  /// points lying along a wall (wall_trace; tracks started on such a wall go).
  std::optional<SonarEcho> echoOf(std::size_t i, const control::Pose2& pose, double range_m, double t_s);
  /// 2a. Only one of the two front sensors hears the object: it is more likely
  /// on that sensor's outer side (the other cone covers the inner side).
  void placeLoneFrontEcho(const control::Pose2& pose, const std::array<double, 4>& ranges_m, SonarEchoes& echo) const;
  /// 2b. Both front sensors hear it: the two ranges fix its bearing
  /// (trilateration across their baseline), the fused point replaces both.
  void triangulateFrontPair(const control::Pose2& pose, SonarEchoes& echo);
  /// 3. Echo i to the nearest track within gate_m, else to a track the camera
  /// saw lately within one detection's error, else a new track.
  void associate(std::size_t i, const control::Pose2& pose, const std::array<double, 4>& ranges_m,
                 const SonarEchoes& echo, double t_s);
  /// 4. Negative information: a sensor whose cone covers a track's place and
  /// hears nothing there (or only well beyond it) contradicts the track.
  void markContradicted(const control::Pose2& pose, const std::array<double, 4>& ranges_m, double t_s);
  /// 5. Confirm (confirm_hits within confirm_window_s) and make people
  /// (moving for moving_for_s, or confirmed by the camera).
  void classifyTracks(double t_s);
  /// 6. Drop tracks contradicted contradiction_ticks in a row, unseen for
  /// coast_s, unconfirmed past the window, or static too long.
  void dropTracks(double t_s);

  /// The camera detected this track within camera.bearing_hold_s of the last step.
  bool cameraSeen(const HumanTrack& t) const { return cameraSeenAt(t, last_t_s_); }

 private:
  bool cameraSeenAt(const HumanTrack& t, double t_s) const {
    return t.camera_seen_s >= 0 && t_s - t.camera_seen_s <= p_.camera.bearing_hold_s;
  }
  void predict(double dt);
  bool nearMap(double x, double y) const;
  /// Persistence cell: first and last time it was hit (< 0: never).
  struct Cell {
    float first_s = -1.0f;
    float last_s = -1.0f;
  };
  Cell* cell(double x, double y);
  /// The point both front sensors see (odometry frame) and its covariance, when the two ranges agree.
  std::optional<std::pair<Eigen::Vector2d, Eigen::Matrix2d>> triangulate(const control::Pose2& pose, double r0,
                                                                          double r1) const;
  void update(HumanTrack& t, const Eigen::Vector2d& z, const Eigen::Matrix2d& r, double t_s);
  /// A track at `z` with covariance `r`, unknown velocity, one hit at t_s (the next id).
  HumanTrack newTrack(const Eigen::Vector2d& z, const Eigen::Matrix2d& r, double t_s);
  /// An echo as a range only: across the beam, the whole cone (what it tells
  /// a track whose bearing the camera gives).
  Eigen::Matrix2d rangeOnly(const SonarEcho& e) const;
  /// The track the camera saw lately that echo `e` lies within one detection's error of (chi2 gate).
  HumanTrack* cameraTrackNear(const control::Pose2& pose, const SonarEcho& e, double t_s);
  /// observeCamera's last phase: the tracks in view that the picture did not
  /// show (matched[j]: track j had a detection) lose person evidence by the
  /// detector's recall at their range, unless a closer track hides them.
  void countCameraMisses(const control::Pose2& pose, const CameraLook& look, const Eigen::Vector2d& lens,
                         std::span<const bool> matched);
  /// Camera evidence on a track's log-odds (and its denial).
  void addPersonEvidence(HumanTrack& t, double logodds);
  /// Records sensor i's echo point and says whether its recent points trace a wall (wall_trace).
  bool tracesWall(std::size_t i, const Eigen::Vector2d& z, const control::Pose2& pose, double t_s);
  /// Echo points of one sensor over the last wall_trace_s (a ring), with the robot's position then.
  struct Trace {
    static constexpr std::size_t kSize = 64;
    std::array<Eigen::Vector2d, kSize> point{};
    std::array<Eigen::Vector2d, kSize> robot{};
    std::array<double, kSize> t{};
    std::size_t head = 0, count = 0;
  };
  std::array<Trace, 4> traces_{};
  /// Walls learned from the side sensors' traces (extended ahead of the robot,
  /// where the front cones' edges meet them), each with the time last confirmed.
  struct Learned {
    geometry::Segment wall;
    double t_s = -1.0;
  };
  std::array<Learned, 4> learned_{};
  bool nearLearned(double x, double y, double t_s) const;

  config::UltrasonicConfig sonar_;
  HumanTrackerParams p_;
  std::vector<geometry::Segment> map_;  // static segments known to the robot (odometry frame), e.g. from the map
  std::vector<HumanTrack> tracks_;
  std::vector<Cell> grid_;
  double grid_origin_x_ = 0, grid_origin_y_ = 0;
  bool have_time_ = false;
  double last_t_s_ = 0;
  int next_id_ = 1;
  TrackerCounters counters_;
  std::array<bool, 4> person_echo_{};
};

}  // namespace inspect::behavior
