#pragma once
// The robot's camera in a simulated run (the scenario suite and the arena):
// every 1 / rate_hz the people it would detect, given to the people tracker
// as robot_client gives the real detector's (RobotApp::feedCamera), the camera
// looking ahead. Two sources: the detector model calibrated on bench_people
// (sim/detector_model.hpp; microseconds a picture), or the real thing - the
// simulator's camera rendered with bench_people's sensor noise and blur and
// the robot's people detector run on it, its boxes turned into bearings and
// foot-row ranges by perception::sightingOf (about 70 ms a picture).
#include <cstdint>
#include <memory>
#include <random>
#include <vector>

#include "shared/behavior/human_awareness.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/perception/people_detector.hpp"
#include "sim/detector_model.hpp"
#include "sim/world_names.hpp"

namespace inspect::sim {

class Simulation;

struct ScenarioCamera {
  bool enabled = true;
  double rate_hz = 5.0;
  DetectorModelParams model;
  bool real = false;
  int width = 640, height = 480;
  double noise_sigma = 3.0, exposure_ms = 8.0;  // bench_people's defaults
  perception::PeopleDetectorOptions detector = [] {  // robot_client's default (config/client.yaml)
    perception::PeopleDetectorOptions o;
    o.floor_band = true;
    return o;
  }();
  // The wide, fixed head (the robot config's wide_camera), when the robot has
  // one: its own model, picture size and detector (docs/human-awareness.md
  // "The wide head"), at the same rate.
  bool wide_head = true;
  DetectorModelParams wide_model = wideHeadModel();
  int wide_width = 480, wide_height = 360;
  perception::PeopleDetectorOptions wide_detector = [] {
    perception::PeopleDetectorOptions o;
    o.group_threshold = 1;
    o.floor_band = true;
    return o;
  }();
};

/// Feeds one run's camera pictures to the tracker, of each head the robot
/// has (the PTZ head looking ahead; the wide head when the robot config has
/// one and `wide_head` is on); `seed` draws the model's misses and noise (and
/// the rendered people's looks).
class CameraLooks {
 public:
  /// `awareness`: the robot's behaviour config: its active look (the PTZ
  /// head turned to undecided tracks beside the robot, when enabled) and the
  /// PTZ head's recall by distance.
  CameraLooks(const World& world, const config::RobotConfig& robot, const behavior::AwarenessConfig& awareness,
              const ScenarioCamera& camera, uint64_t seed);
  ~CameraLooks();
  CameraLooks(const CameraLooks&) = delete;
  CameraLooks& operator=(const CameraLooks&) = delete;

  /// Call every tick before the frame reaches the decision core: a picture
  /// of each head when one is due.
  void beforeFrame(const Simulation& sim, behavior::HumanAwareness& aw, double t_s);
  /// The active look's figures so far (looks started, time the PTZ head was off the path).
  const behavior::ActiveLookState& activeLook() const { return look_state_; }

 private:
  class Real;
  struct Head {
    config::CameraMount mount;
    bool wide = false;
    const DetectorModelParams* model = nullptr;
    std::mt19937_64 rng;
    std::unique_ptr<Real> real;
  };
  const World& world_;
  const ScenarioCamera& camera_;
  std::vector<Head> heads_;
  double next_look_s_ = 0.0;
  std::vector<PersonDisc> discs_;
  behavior::ActiveLookParams look_;
  behavior::RecallTable ptz_recall_;
  behavior::ActiveLookState look_state_;
};

}  // namespace inspect::sim
