#include "sim/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace inspect::sim {
namespace {
// Independent noise streams per sensor from one --seed.
uint64_t subSeed(uint64_t seed, uint64_t stream) { return seed * 0x9E3779B97F4A7C15ull + stream; }

std::string channelList(const config::GasConfig& cfg) {
  std::string s;
  for (const auto& c : cfg.channels) s += (s.empty() ? "" : ", ") + c.name;
  return s.empty() ? "none" : s;
}

[[noreturn]] void gasNameError(const World& w, const std::string& key, const std::string& name,
                               const config::GasConfig& cfg) {
  throw config::ConfigError(w.source_file + ": " + key + ": '" + name +
                            "' is not a gas channel of the robot (robot config gas.channels: " + channelList(cfg) +
                            ")");
}

// Leaks must name the robot's channels (checked before the grid is built).
const World& checkGasNames(const config::GasConfig& cfg, const World& w) {
  for (std::size_t i = 0; i < w.gas.sources.size(); ++i)
    if (cfg.find(w.gas.sources[i].gas) < 0)
      gasNameError(w, "gas.sources[" + std::to_string(i) + "].gas", w.gas.sources[i].gas, cfg);
  return w;
}

std::vector<GasSensorFault> resolveGasFaults(const config::GasConfig& cfg, const World& w) {
  std::vector<GasSensorFault> out;
  for (std::size_t i = 0; i < w.gas.faults.size(); ++i) {
    const auto& f = w.gas.faults[i];
    const int ch = cfg.find(f.channel);
    if (ch < 0) gasNameError(w, "gas.faults[" + std::to_string(i) + "].channel", f.channel, cfg);
    out.push_back({static_cast<std::size_t>(ch), f.kind, f.start_s, f.end_s});
  }
  return out;
}

std::string fmtSeconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", s);
  return buf;
}
}  // namespace

Simulation::Simulation(const config::RobotConfig& robot, World world, uint64_t seed, SimObserver* observer)
    : world_(std::move(world)),
      plant_(robot, world_),
      motor_delay_(plant_.motors().left.dead_time_s, plant_.motors().right.dead_time_s),
      ultrasonic_(robot.ultrasonic, subSeed(seed, 1)),
      mcu_(robot, subSeed(seed, 2), observer),
      observer_(observer),
      body_{robot.geometry.body_radius_m, robot.geometry.wheel_radius_m, robot.geometry.track_m},
      people_{.crowd = PedestrianCrowd(world_, observer), .contact = std::vector<bool>(world_.pedestrians.size(), false)},
      gas_{.cfg = robot.gas,
           .model = GasModel(checkGasNames(robot.gas, world_)),
           .sensors = GasSensors(robot.gas, resolveGasFaults(robot.gas, world_), subSeed(seed, 3)),
           .fault_on = std::vector<bool>(world_.gas.faults.size(), false)} {
  checkStartPose(world_, body_.radius_m);
  state_.pose = world_.start;
  for (const auto& ch : gas_.cfg.channels) {
    GasChannelMap m;
    m.background = ch.background;
    m.field = gas_.model.field(ch.name);
    for (const auto& x : ch.cross)
      if (const int f = gas_.model.field(x.gas); f >= 0) m.cross.emplace_back(f, x.factor);
    gas_.channel_maps.push_back(std::move(m));
  }
  // The sensors have been standing at the start pose: no start-up transient.
  const GasValues truth = trueGas(gasInlet());
  gas_.sensors.settle(truth);
}

Vec2 Simulation::gasInlet() const {
  const auto& p = state_.pose;
  const double c = std::cos(p.theta_rad), s = std::sin(p.theta_rad);
  return {p.x_m + c * gas_.cfg.inlet_x_m - s * gas_.cfg.inlet_y_m,
          p.y_m + s * gas_.cfg.inlet_x_m + c * gas_.cfg.inlet_y_m};
}

Simulation::GasValues Simulation::trueGas(Vec2 p) const {
  GasValues fields{}, out{};
  gas_.model.concentrations(p, fields);
  for (std::size_t i = 0; i < gas_.channel_maps.size() && i < out.size(); ++i) {
    const auto& m = gas_.channel_maps[i];
    double v = m.background + (m.field >= 0 ? fields[static_cast<std::size_t>(m.field)] : 0.0);
    for (const auto& [f, factor] : m.cross) v += factor * fields[static_cast<std::size_t>(f)];
    out[i] = v;
  }
  return out;
}

double Simulation::trueConcentration(int channel, Vec2 p) const {
  if (channel < 0 || static_cast<std::size_t>(channel) >= std::min(gas_.channel_maps.size(), GasValues{}.size()))
    return std::numeric_limits<double>::quiet_NaN();
  return trueGas(p)[static_cast<std::size_t>(channel)];
}

void Simulation::reportGasStart() {
  if (gas_.reported) return;
  gas_.reported = true;
  if (!observer_) return;
  if (!gas_.cfg.channels.empty()) {
    std::string d;
    for (const auto& c : gas_.cfg.channels) d += (d.empty() ? "" : " ") + c.name + "=" + c.unit;
    observer_->onEvent(timeS(), "gas_channels", d);
  }
  for (const auto& s : world_.gas.sources) {
    char detail[256];
    std::snprintf(detail, sizeof detail, "name=%s gas=%s x=%.3f y=%.3f rate=%g start_s=%s end_s=%s", s.name.c_str(),
                  s.gas.c_str(), s.position.x, s.position.y, s.rate, fmtSeconds(s.start_s).c_str(),
                  fmtSeconds(s.end_s).c_str());
    observer_->onEvent(timeS(), "gas_source", detail);
  }
}

void Simulation::sampleGas(McuInputs& in) {
  const std::size_t n = std::min(gas_.channel_maps.size(), GasValues{}.size());
  if (n == 0) return;
  const auto& faults = gas_.sensors.faults();
  for (std::size_t i = 0; i < faults.size(); ++i) {
    const bool on = timeS() >= faults[i].start_s && timeS() < faults[i].end_s;
    if (on == gas_.fault_on[i]) continue;
    gas_.fault_on[i] = on;
    if (observer_) {
      const auto& f = world_.gas.faults[i];
      observer_->onEvent(timeS(), on ? "gas_fault_start" : "gas_fault_end",
                         "channel=" + f.channel + (f.kind == GasFaultKind::Stuck ? " kind=stuck" : " kind=dropout"));
    }
  }
  const Vec2 inlet = gasInlet();
  const GasValues truth = trueGas(inlet);
  const double dt_s =
      gas_.last_sample_ms < 0 ? 0.0 : static_cast<double>(static_cast<int64_t>(t_ms_) - gas_.last_sample_ms) / 1000.0;
  gas_.last_sample_ms = static_cast<int64_t>(t_ms_);
  in.gas_raw = gas_.sensors.sample(timeS(), dt_s, {truth.data(), n});
  if (observer_ && t_ms_ % kGasLogPeriod_ms == 0) {
    GasValues reading{};
    for (std::size_t i = 0; i < n; ++i) reading[i] = gas_.sensors.reading(i);
    observer_->onGas({timeS(), inlet.x, inlet.y, {truth.data(), n}, {reading.data(), n}});
  }
}

behavior::Agent Simulation::robotBody() const {
  behavior::Agent r;
  r.position_m = {state_.pose.x_m, state_.pose.y_m};
  const double v = control::twistFromWheels(state_.wheel, body_.wheel_radius_m, body_.track_m).v_m_s;
  r.velocity_m_s = {v * std::cos(state_.pose.theta_rad), v * std::sin(state_.pose.theta_rad)};
  r.radius_m = body_.radius_m;
  return r;
}

void Simulation::receive(std::span<const uint8_t> bytes) {
  if (hil_) {
    hil_->receive(bytes, t_ms_);
  } else {
    mcu_.receive(bytes, t_ms_);
  }
}

void Simulation::emitFrame() {
  McuInputs in;
  in.truth = state_;
  if (hil_) {
    // The firmware builds the frames: here the gas sensors are sampled for its ADC inputs.
    sampleGas(in);
    hil_gas_raw_ = in.gas_raw;
    // The truth's set-points: the firmware's in force (its speed loop's targets).
    if (observer_) observer_->onSample({timeS(), state_.pose, state_.wheel, hil_->firmwareSetpoints(), 0});
  } else {
    in.ultrasonic_mm = ultrasonic_.measureAllMm(world_, state_.pose, people_.crowd.circles());
    in.grayscale = GrayscaleModel::read(world_, state_.pose);
    sampleGas(in);
    const auto frame = mcu_.sendSensorFrame(t_ms_, in, tx_);
    if (observer_) observer_->onSample({timeS(), state_.pose, state_.wheel, mcu_.setpoints(), frame.faults});
  }
  if (t_ms_ % kPedestrianPeriod_ms == 0) emitPedestrians();
}

void Simulation::useHilFirmware(const config::RobotConfig& robot) {
  hil_ = std::make_unique<HilMcu>(robot, observer_);
  if (observer_) observer_->onEvent(timeS(), "hil", "the MCU is the firmware on the HIL link");
}

void Simulation::stepHil() {
  // A ping is answered at once with the range now (the echo returns within the
  // firmware's 30 ms slot); the other readings go first whenever due
  // (HilMcu::sensorsDue), the encoders every 10 ms.
  if (const int s = hil_->pendingPing(); s >= 0)
    hil_->answerPing(ultrasonic_.measureMm(world_, state_.pose, s, people_.crowd.circles()));
  if (hil_->sensorsDue(t_ms_)) {
    if (gas_.last_sample_ms < 0) {
      // Due before the first sensor frame's step sampled the gas (the board
      // spoke first): sample it now, or its first readings would be zero (an
      // oxygen channel at 0 %vol raised robot_client's O2 alarms).
      McuInputs in;
      in.truth = state_;
      sampleGas(in);
      hil_gas_raw_ = in.gas_raw;
    }
    hil_->sendSensors(t_ms_, GrayscaleModel::read(world_, state_.pose), hil_gas_raw_, tx_);
  }
  // The encoders: a frame held back is no loss, the next carries newer counts (and the board extrapolates).
  if (t_ms_ % HilMcu::kInputPeriod_ms == 0) hil_->sendEncoders(state_, t_ms_, tx_);
}

void Simulation::emitPedestrians() {
  if (!observer_) return;
  for (std::size_t i = 0; i < people_.crowd.size(); ++i) {
    if (!people_.crowd.present(i)) continue;
    const auto& a = people_.crowd.agent(i);
    const double dist = std::hypot(a.position_m.x() - state_.pose.x_m, a.position_m.y() - state_.pose.y_m);
    observer_->onPedestrian({timeS(), people_.crowd.script(i).id, a.position_m.x(), a.position_m.y(), a.velocity_m_s.x(),
                             a.velocity_m_s.y(), dist});
  }
}

void Simulation::checkPersonContacts() {
  for (std::size_t i = 0; i < people_.crowd.size(); ++i) {
    if (!people_.crowd.present(i)) continue;
    const auto& a = people_.crowd.agent(i);
    const double gap = std::hypot(a.position_m.x() - state_.pose.x_m, a.position_m.y() - state_.pose.y_m) -
                       body_.radius_m - a.radius_m;
    if (gap < 0.0 && !people_.contact[i]) {
      people_.contact[i] = true;
      ++people_.collisions;
      if (observer_) {
        char detail[192];
        std::snprintf(detail, sizeof detail, "id=%s x=%.3f y=%.3f person_x=%.3f person_y=%.3f",
                      people_.crowd.script(i).id.c_str(), state_.pose.x_m, state_.pose.y_m, a.position_m.x(),
                      a.position_m.y());
        observer_->onEvent(timeS(), "collision_person", detail);
      }
    } else if (people_.contact[i] && gap > kContactRelease_m) {
      people_.contact[i] = false;
    }
  }
}

void Simulation::step() {
  if (hil_) {
    stepHil();
  } else {
    mcu_.tick(t_ms_);
  }
  people_.crowd.reportInitial();
  reportGasStart();
  if (t_ms_ % kGasPeriod_ms == 0) gas_.model.advanceTo(timeS());  // fields at t for this step's frame
  if (t_ms_ % kFramePeriod_ms == 0) emitFrame();
  const double dt_s = static_cast<double>(kStep_ms) / 1000.0;
  // Both from the state at t: the people react to where the robot is now.
  if (people_.wait_for_motion && !people_.started) {
    const auto sp = wheelTargets();
    if (sp.left_rad_s != 0.0 || sp.right_rad_s != 0.0) {
      people_.started = true;
      people_.t0_s = timeS();
      if (observer_) observer_->onEvent(timeS(), "people_clock_start", "first wheel motion");
    }
  }
  if (!people_.wait_for_motion || people_.started) people_.crowd.step(timeS() - people_.t0_s, dt_s, robotBody());
  const auto r = plant_.step(state_, motor_delay_.apply(timeS(), wheelTargets()), dt_s);
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
  } else if (in_contact_ && r.clearance_m > body_.radius_m + kContactRelease_m) {
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
