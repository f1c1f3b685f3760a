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
  perception::PeopleDetectorOptions detector;   // robot_client's default (config/client.yaml)
};

/// Feeds one run's camera pictures to the tracker; `seed` draws the model's
/// misses and noise (and the rendered people's looks).
class CameraLooks {
 public:
  CameraLooks(const World& world, const config::CameraMount& mount, const ScenarioCamera& camera, uint64_t seed);
  ~CameraLooks();
  CameraLooks(const CameraLooks&) = delete;
  CameraLooks& operator=(const CameraLooks&) = delete;

  /// Call every tick before the frame reaches the decision core: a picture
  /// when one is due.
  void beforeFrame(const Simulation& sim, behavior::HumanAwareness& aw, double t_s);

 private:
  class Real;
  const World& world_;
  config::CameraMount mount_;
  const ScenarioCamera& camera_;
  std::mt19937_64 rng_;
  std::unique_ptr<Real> real_;
  double next_look_s_ = 0.0;
  std::vector<PersonDisc> discs_;
};

}  // namespace inspect::sim
