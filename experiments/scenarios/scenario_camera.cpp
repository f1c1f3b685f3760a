#include "experiments/scenarios/scenario_camera.hpp"

#include <cmath>

#include "shared/perception/camera_geometry.hpp"
#include "sim/camera_view.hpp"
#include "sim/simulation.hpp"

namespace inspect::sim {

/// The simulator's camera and the robot's people detector.
class CameraLooks::Real {
 public:
  Real(const World& w, const config::CameraMount& mount, bool wide, const ScenarioCamera& c, uint64_t seed)
      : view_(w, mount, wide ? c.wide_width : c.width, wide ? c.wide_height : c.height, style(c, seed)),
        detector_(wide ? c.wide_detector : c.detector), wide_(wide) {
    cam_.width = wide ? c.wide_width : c.width;
    cam_.height = wide ? c.wide_height : c.height;
    cam_.mount = mount;
  }

  /// One picture of the robot's view now (the camera ahead), detected.
  behavior::CameraLook look(const Simulation& sim, double pan_rad, double t_s) {
    scene_.robot = sim.state().pose;
    scene_.pan_rad = pan_rad;
    scene_.sim_time_s = t_s;
    peopleInView(sim.pedestrians(), scene_.people);
    view_.render(scene_, static_cast<uint64_t>(t_s * 1e6), frame_index_++, frame_);
    behavior::CameraLook look;
    look.lens_x_m = cam_.mount.x_m;
    look.lens_y_m = cam_.mount.y_m;
    look.axis_rad = pan_rad;
    look.half_fov_rad = cam_.mount.hfov_deg * M_PI / 360.0;
    look.wide = wide_;
    cam_.pan_rad = pan_rad;
    for (const auto& b : detector_.detect(frame_, &cam_)) {
      const auto s = perception::sightingOf(b.box, cam_);
      look.add({s.bearing_rad, s.range_m.value_or(-1.0)});
    }
    return look;
  }

 private:
  static CameraViewStyle style(const ScenarioCamera& c, uint64_t seed) {
    CameraViewStyle s;
    s.look_seed = static_cast<uint32_t>(seed);
    s.noise_sigma = c.noise_sigma;
    s.exposure_ms = c.exposure_ms;
    return s;
  }
  CameraView view_;
  perception::PeopleDetector detector_;
  perception::CameraPose cam_;
  CameraScene scene_;
  cv::Mat frame_;
  uint32_t frame_index_ = 0;
  bool wide_;
};

CameraLooks::CameraLooks(const World& world, const config::RobotConfig& robot,
                         const behavior::AwarenessConfig& awareness, const ScenarioCamera& camera, uint64_t seed)
    : world_(world), camera_(camera), look_(awareness.active_look), ptz_recall_(awareness.tracker.camera.recall) {
  if (!camera.enabled) return;
  heads_.push_back({robot.camera, false, &camera.model, std::mt19937_64(seed * 7919 + 17), nullptr});
  if (camera.wide_head && robot.wide_camera)
    heads_.push_back({*robot.wide_camera, true, &camera.wide_model, std::mt19937_64(seed * 7919 + 29), nullptr});
  if (camera.real)
    for (auto& h : heads_) h.real = std::make_unique<Real>(world, h.mount, h.wide, camera, seed);
}

CameraLooks::~CameraLooks() = default;

void CameraLooks::beforeFrame(const Simulation& sim, behavior::HumanAwareness& aw, double t_s) {
  if (heads_.empty() || t_s + 1e-9 < next_look_s_) return;
  next_look_s_ = t_s + 1.0 / camera_.rate_hz;
  // The model on the true scene; the tracker places it at the true pose (the
  // odometry's drift over a 9 m run is centimetres).
  discs_.clear();
  const auto& crowd = sim.pedestrians();
  for (std::size_t i = 0; i < crowd.size() && !camera_.real; ++i)
    if (crowd.present(i)) {
      const auto& a = crowd.agent(i);
      discs_.push_back({a.position_m.x(), a.position_m.y(), a.radius_m});
    }
  for (auto& h : heads_) {
    // The PTZ head where the active look points it (ahead when off); no picture while it turns.
    double pan = 0.0;
    if (!h.wide && look_.enabled) {
      pan = behavior::activeLookPan(look_state_, look_, aw.tracker().tracks(), sim.state().pose, h.mount.x_m,
                                    h.mount.y_m, h.mount.hfov_deg * M_PI / 360.0, ptz_recall_, t_s);
      if (behavior::activeLookTurning(look_state_, t_s)) continue;
    }
    if (h.real) {
      aw.observeCamera(sim.state().pose, h.real->look(sim, pan, t_s));
      continue;
    }
    behavior::CameraLook look = detectPeople(world_, sim.state().pose, h.mount, pan, discs_, *h.model, h.rng);
    look.wide = h.wide;
    aw.observeCamera(sim.state().pose, look);
  }
}

}  // namespace inspect::sim
