#include "sim/simulation.hpp"

#include <cmath>
#include <cstdio>

namespace inspect::sim {
namespace {
// Independent noise streams per sensor from one --seed.
uint64_t subSeed(uint64_t seed, uint64_t stream) { return seed * 0x9E3779B97F4A7C15ull + stream; }
}  // namespace

Simulation::Simulation(const config::RobotConfig& robot, World world, uint64_t seed, SimObserver* observer)
    : world_(std::move(world)),
      plant_(robot, world_),
      ultrasonic_(robot.ultrasonic, subSeed(seed, 1)),
      mcu_(robot, subSeed(seed, 2), observer),
      observer_(observer),
      crowd_(world_, observer),
      body_radius_m_(robot.geometry.body_radius_m),
      wheel_radius_m_(robot.geometry.wheel_radius_m),
      track_m_(robot.geometry.track_m),
      person_contact_(world_.pedestrians.size(), false) {
  checkStartPose(world_, body_radius_m_);
  state_.pose = world_.start;
}

behavior::Agent Simulation::robotBody() const {
  behavior::Agent r;
  r.position_m = {state_.pose.x_m, state_.pose.y_m};
  const double v = control::twistFromWheels(state_.wheel, wheel_radius_m_, track_m_).v_m_s;
  r.velocity_m_s = {v * std::cos(state_.pose.theta_rad), v * std::sin(state_.pose.theta_rad)};
  r.radius_m = body_radius_m_;
  return r;
}

void Simulation::receive(std::span<const uint8_t> bytes) { mcu_.receive(bytes, t_ms_); }

void Simulation::emitFrame() {
  McuInputs in;
  in.truth = state_;
  in.ultrasonic_mm = ultrasonic_.measureAllMm(world_, state_.pose, crowd_.circles());
  in.grayscale = GrayscaleModel::read(world_, state_.pose);
  const auto frame = mcu_.sendSensorFrame(t_ms_, in, tx_);
  if (observer_) observer_->onSample({timeS(), state_.pose, state_.wheel, mcu_.setpoints(), frame.faults});
  if (t_ms_ % kPedestrianPeriod_ms == 0) emitPedestrians();
}

void Simulation::emitPedestrians() {
  if (!observer_) return;
  for (std::size_t i = 0; i < crowd_.size(); ++i) {
    if (!crowd_.present(i)) continue;
    const auto& a = crowd_.agent(i);
    const double dist = std::hypot(a.position_m.x() - state_.pose.x_m, a.position_m.y() - state_.pose.y_m);
    observer_->onPedestrian({timeS(), crowd_.script(i).id, a.position_m.x(), a.position_m.y(), a.velocity_m_s.x(),
                             a.velocity_m_s.y(), dist});
  }
}

void Simulation::checkPersonContacts() {
  for (std::size_t i = 0; i < crowd_.size(); ++i) {
    if (!crowd_.present(i)) continue;
    const auto& a = crowd_.agent(i);
    const double gap = std::hypot(a.position_m.x() - state_.pose.x_m, a.position_m.y() - state_.pose.y_m) -
                       body_radius_m_ - a.radius_m;
    if (gap < 0.0 && !person_contact_[i]) {
      person_contact_[i] = true;
      ++person_collisions_;
      if (observer_) {
        char detail[192];
        std::snprintf(detail, sizeof detail, "id=%s x=%.3f y=%.3f person_x=%.3f person_y=%.3f",
                      crowd_.script(i).id.c_str(), state_.pose.x_m, state_.pose.y_m, a.position_m.x(),
                      a.position_m.y());
        observer_->onEvent(timeS(), "collision_person", detail);
      }
    } else if (person_contact_[i] && gap > kContactRelease_m) {
      person_contact_[i] = false;
    }
  }
}

void Simulation::step() {
  mcu_.tick(t_ms_);
  crowd_.reportInitial();
  if (t_ms_ % kFramePeriod_ms == 0) emitFrame();
  const double dt_s = static_cast<double>(kStep_ms) / 1000.0;
  // Both from the state at t: the people react to where the robot is now.
  if (people_wait_ && !people_started_) {
    const auto sp = mcu_.setpoints();
    if (sp.left_rad_s != 0.0 || sp.right_rad_s != 0.0) {
      people_started_ = true;
      people_t0_s_ = timeS();
      if (observer_) observer_->onEvent(timeS(), "people_clock_start", "first wheel motion");
    }
  }
  if (!people_wait_ || people_started_) crowd_.step(timeS() - people_t0_s_, dt_s, robotBody());
  const auto r = plant_.step(state_, mcu_.setpoints(), dt_s);
  state_ = r.state;
  checkPersonContacts();
  if (r.blocked && !in_contact_) {
    in_contact_ = true;
    ++collisions_;
    if (observer_) {
      char detail[96];
      std::snprintf(detail, sizeof detail, "x=%.3f y=%.3f theta=%.3f", state_.pose.x_m, state_.pose.y_m,
                    state_.pose.theta_rad);
      observer_->onEvent(timeS(), "collision", detail);
    }
  } else if (in_contact_ && r.clearance_m > body_radius_m_ + kContactRelease_m) {
    in_contact_ = false;
  }
  t_ms_ += kStep_ms;
}

void Simulation::advanceTo(uint64_t t_ms) {
  while (t_ms_ < t_ms) step();
}

void Simulation::takeTx(std::vector<uint8_t>& out) {
  out.clear();
  out.swap(tx_);
}

}  // namespace inspect::sim
