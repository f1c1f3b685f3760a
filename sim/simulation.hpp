#pragma once
// The whole simulated robot and world in sim time: plant, sensors, MCU,
// pedestrians and gas, stepped at 1 kHz with a sensor frame every 10 ms. No I/O
// and no clocks: bytes go in through receive(), frames come out of takeTx().
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "shared/config/robot_config.hpp"
#include "sim/gas_model.hpp"
#include "sim/gas_sensor.hpp"
#include "sim/grayscale_model.hpp"
#include "sim/hil_mcu.hpp"
#include "sim/mcu_emulator.hpp"
#include "sim/pedestrian_crowd.hpp"
#include "sim/robot_plant.hpp"
#include "sim/sim_observer.hpp"
#include "sim/ultrasonic_model.hpp"
#include "sim/world_names.hpp"

namespace inspect::sim {

/// World + robot + MCU, advanced in fixed 1 ms steps.
class Simulation {
 public:
  static constexpr uint64_t kStep_ms = 1;
  static constexpr uint64_t kFramePeriod_ms = 10;
  /// Pedestrian ground truth (P rows) every 100 ms of sim time.
  static constexpr uint64_t kPedestrianPeriod_ms = 100;
  /// Contact ends (and a new collision may be logged) once clearance exceeds body radius + this.
  static constexpr double kContactRelease_m = 0.005;
  /// The gas fields advance every 50 ms of sim time.
  static constexpr uint64_t kGasPeriod_ms = 50;
  /// Gas ground truth (SimObserver::onGas, G rows) every 100 ms of sim time.
  static constexpr uint64_t kGasLogPeriod_ms = 100;

  /// Throws config::ConfigError when the start pose overlaps an obstacle, or a
  /// leak or scripted gas fault names a gas that is not a channel of robot.gas.
  Simulation(const config::RobotConfig& robot, World world, uint64_t seed, SimObserver* observer = nullptr);
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  /// When on, the pedestrians stand at their start points and their clock
  /// (start_s, pauses) starts at the first non-zero wheel set-point, so that a
  /// scenario plays the same whenever the robot starts. Off by default.
  void setPeopleWaitForMotion(bool on) { people_.wait_for_motion = on; }
  /// Sim time at which the pedestrians' clock started (0 unless waiting; < 0 while still waiting).
  double peopleClockStartS() const { return people_.wait_for_motion && !people_.started ? -1.0 : people_.t0_s; }

  /// From now on the MCU is the real firmware, hardware-in-the-loop (mcu_sim
  /// --hil, sim/hil_mcu.hpp): receive() takes its board's HIL bytes, takeTx()
  /// gives what its peripherals read (polled every HilMcu::kPollPeriod_ms), and the
  /// motors follow its PWM duty. The emulator stays idle.
  void useHilFirmware(const config::RobotConfig& robot);
  /// The HIL link's end, when useHilFirmware() was called.
  const HilMcu* hilMcu() const { return hil_.get(); }
  /// How often takeTx() may have something: the sensor frame's period, or the HIL link's poll.
  uint64_t outputPeriodMs() const { return hil_ ? HilMcu::kPollPeriod_ms : kFramePeriod_ms; }
  /// The camera mount's pan and tilt (rad): the emulator's PTZ set-point, or
  /// where the firmware's servo pulses put it.
  std::array<double, 2> cameraPanTilt() const {
    if (hil_) return hil_->ptzRad();
    return {mcu_.ptz().pan_0p1mrad * 1e-4, mcu_.ptz().tilt_0p1mrad * 1e-4};
  }
  /// The speeds the motors run toward now: the emulator's set-points, or the firmware's duty's.
  control::WheelSpeeds wheelTargets() const { return hil_ ? hil_->motorTargets() : mcu_.setpoints(); }

  /// Bytes from the host (or the HIL board), applied at the current sim time.
  void receive(std::span<const uint8_t> bytes);
  /// One 1 ms step: MCU timers, a sensor frame when due, physics (robot and pedestrians).
  void step();
  /// Steps until timeMs() == t_ms (no-op when already there).
  void advanceTo(uint64_t t_ms);
  /// Moves the bytes of the frames produced so far into out (out is cleared first).
  void takeTx(std::vector<uint8_t>& out);

  uint64_t timeMs() const { return t_ms_; }
  double timeS() const { return static_cast<double>(t_ms_) / 1000.0; }
  const PlantState& state() const { return state_; }
  const McuEmulator& mcu() const { return mcu_; }
  const World& world() const { return world_; }
  uint64_t collisions() const { return collisions_; }
  const PedestrianCrowd& pedestrians() const { return people_.crowd; }
  /// Robot-person contacts so far (one per contact, like collisions()).
  uint64_t personCollisions() const { return people_.collisions; }
  /// The robot's body as the pedestrians see it (true pose and velocity).
  behavior::Agent robotBody() const;

  /// The gas concentration fields (as of the last 50 ms update).
  const GasModel& gas() const { return gas_.model; }
  /// The simulated gas sensors (responses, last readings).
  const GasSensors& gasSensors() const { return gas_.sensors; }
  /// World position of the gas sampling inlet at the current pose.
  Vec2 gasInlet() const;
  /// What gas channel `channel` (slot of robot.gas) would truly read at p now,
  /// before the sensor's response: background + its gas + cross factor x each
  /// other gas. NaN for a channel that is not configured.
  double trueConcentration(int channel, Vec2 p) const;

 private:
  using GasValues = std::array<double, serial::kGasChannels>;
  // A channel's true value in terms of the gas fields.
  struct GasChannelMap {
    double background = 0.0;
    int field = -1;                            // its own gas, or -1 when nothing leaks it
    std::vector<std::pair<int, double>> cross;  // (field, factor) of the other gases that leak
  };
  void emitFrame();
  void stepHil();
  void emitPedestrians();
  void checkPersonContacts();
  void reportGasStart();
  void sampleGas(McuInputs& in);
  GasValues trueGas(Vec2 p) const;

  World world_;
  RobotPlant plant_;
  control::SetpointDelay motor_delay_;  // the plant's dead time (world `plant:`)
  UltrasonicModel ultrasonic_;
  McuEmulator mcu_;
  std::unique_ptr<HilMcu> hil_;
  std::array<uint16_t, serial::kGasChannels> hil_gas_raw_{};  // the gas sensors' last readings, for the HIL inputs
  SimObserver* observer_;
  PlantState state_;
  uint64_t t_ms_ = 0;
  bool in_contact_ = false;
  uint64_t collisions_ = 0;
  std::vector<uint8_t> tx_;

  struct Body {  // robot.yaml geometry
    double radius_m;
    double wheel_radius_m;
    double track_m;
  } body_;

  struct People {
    PedestrianCrowd crowd;
    std::vector<bool> contact;     // per pedestrian: overlapping the robot now
    uint64_t collisions = 0;
    bool wait_for_motion = false;  // their clock starts at the robot's first wheel motion
    bool started = false;
    double t0_s = 0.0;
  } people_;

  struct Gas {  // fields, sensors, how channels read the fields
    config::GasConfig cfg;
    GasModel model;
    GasSensors sensors;
    std::vector<GasChannelMap> channel_maps{};
    std::vector<bool> fault_on;  // per scripted fault: active at the last frame
    bool reported = false;
    int64_t last_sample_ms = -1;
  } gas_;
};

}  // namespace inspect::sim
