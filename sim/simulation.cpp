#include "sim/simulation.hpp"

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
      body_radius_m_(robot.geometry.body_radius_m) {
  checkStartPose(world_, body_radius_m_);
  state_.pose = world_.start;
}

void Simulation::receive(std::span<const uint8_t> bytes) { mcu_.receive(bytes, t_ms_); }

void Simulation::emitFrame() {
  McuInputs in;
  in.truth = state_;
  in.ultrasonic_mm = ultrasonic_.measureAllMm(world_, state_.pose);
  in.grayscale = GrayscaleModel::read(world_, state_.pose);
  const auto frame = mcu_.sendSensorFrame(t_ms_, in, tx_);
  if (observer_) observer_->onSample({timeS(), state_.pose, state_.wheel, mcu_.setpoints(), frame.faults});
}

void Simulation::step() {
  mcu_.tick(t_ms_);
  if (t_ms_ % kFramePeriod_ms == 0) emitFrame();
  const auto r = plant_.step(state_, mcu_.setpoints(), static_cast<double>(kStep_ms) / 1000.0);
  state_ = r.state;
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
