#pragma once
// A world file's `gas:` section: how air carries leaked gas (diffusivity,
// ventilation, airflow, grid), the leaks, and scripted sensor faults
// (docs/world-format.md). The dispersion itself: sim/gas_model.hpp.
#include <limits>
#include <string>
#include <vector>

#include "shared/config/config_node.hpp"
#include "shared/geometry/vec2.hpp"

namespace inspect::world {

using geometry::Vec2;

struct World;

/// One leak: a point source emitting `rate` from start_s (inclusive) to end_s (exclusive).
struct GasSource {
  std::string name;       // unique in the world; in the truth log's gas_source event
  std::string gas;        // a channel name of the robot's gas config (checked by Simulation)
  Vec2 position;          // world frame, m
  double rate = 0.0;      // channel unit x m^2/s (source strength of the 2-D model)
  double start_s = 0.0;   // < 0: the leak was already on that long when the simulation starts
  double end_s = std::numeric_limits<double>::infinity();
  bool activeAt(double t_s) const { return t_s >= start_s && t_s < end_s; }
};

/// What a scripted sensor fault does to a channel's raw value.
enum class GasFaultKind {
  Stuck,    // frozen at the raw value it had when the fault began
  Dropout,  // config::kGasNoData (the MCU also sets kFaultGasSensor)
};

/// A scripted fault of one gas channel over [start_s, end_s).
struct GasFault {
  std::string channel;  // a channel name of the robot's gas config (checked by Simulation)
  GasFaultKind kind = GasFaultKind::Stuck;
  double start_s = 0.0;
  double end_s = std::numeric_limits<double>::infinity();
  bool activeAt(double t_s) const { return t_s >= start_s && t_s < end_s; }
};

/// The `gas` section; the defaults apply when it (or a key) is absent.
struct GasSpec {
  double diffusivity_m2_s = 0.05;   // effective (turbulent) diffusivity D
  double ventilation_per_s = 0.05;  // first-order removal rate k
  Vec2 airflow_m_s;                 // uniform airflow u (advection)
  double cell_m = 0.1;              // grid cell size h
  std::vector<GasSource> sources;
  std::vector<GasFault> faults;
};

/// Earliest start_s of a leak when ventilation_per_s is 0 (the field never settles; pre-integration is explicit).
inline constexpr double kGasMaxPreRunNoVentilation_s = 600.0;

/// Reads root's `gas` section (walls and obstacles of `world` already loaded:
/// leaks must lie inside the walls' bounding box, not inside an obstacle nor
/// on a wall). Throws config::ConfigError naming file, key and reason.
GasSpec readGasSpec(const config::ConfigNode& root, const World& world);

}  // namespace inspect::world
