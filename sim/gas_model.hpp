#pragma once
// Dispersion of leaked gas over the world's floor plan: one 2-D concentration
// field per gas that has leaks, on a square grid over the walls' and
// obstacles' bounding box (+ margin),
//   dc/dt = D lap(c) - u . grad(c) - k c + sum of leaks,
// finite volumes with upwind advection, no flux through walls and obstacle
// edges, explicit sub-steps within the stability limit. Leaks that started
// before t = 0 are pre-integrated (steady state solved directly when they are
// old enough); a field at the steady state of its leaks is not stepped until
// a leak starts or stops. Model, boundary conditions, limits and costs:
// docs/simulator.md.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "sim/world_names.hpp"

namespace inspect::sim {

/// The gas concentration fields of a world in sim time.
class GasModel {
 public:
  /// Free cells around the walls' bounding box: max(this, 2 cells).
  static constexpr double kMargin_m = 0.5;
  /// Sub-steps use at most this fraction of the largest stable explicit step.
  static constexpr double kStabilityFactor = 0.9;
  /// A leak older than ln(1/this)/k at t = 0 starts at its steady state.
  static constexpr double kSettleTolerance = 1e-3;
  /// Grid size limit (memory).
  static constexpr std::size_t kMaxCells = 2'000'000;
  /// Work limit: cells x sub-steps per second of sim time, summed over the fields.
  static constexpr double kMaxCellUpdatesPerSimS = 2e8;

  /// Builds the grid (only when the world has leaks) and pre-integrates the
  /// leaks that started before t = 0. Throws config::ConfigError naming the
  /// world file and `gas.cell_m` when the grid would be too large or too costly.
  explicit GasModel(const World& world);

  /// Advances every field to sim time t_s (no-op when already there). A leak
  /// emits during each sub-step that starts within [start_s, end_s).
  void advanceTo(double t_s);
  /// Sim time the fields are at.
  double timeS() const { return t_s_; }

  /// Gases that have leaks, one field each, in the order of their first leak in the world file.
  const std::vector<std::string>& gases() const { return gases_; }
  /// Field index of `gas`, or -1 when no leak emits it.
  int field(std::string_view gas) const;
  /// Concentration of field f at p (channel unit): bilinear over the four
  /// nearest cell centres that are free and not behind a wall from p; 0 inside
  /// an obstacle and off the grid.
  double concentration(int f, Vec2 p) const;
  /// Every field at p at once (out[f] for f < gases().size()).
  void concentrations(Vec2 p, std::span<double> out) const;
  /// Total amount of field f on the grid: sum of c x cell area (unit x m^2).
  double mass(int f) const;
  /// True while field f is the steady state of its leaks and none has started
  /// or stopped since t = 0: advanceTo() leaves it as it is (nothing would change).
  bool steady(int f) const;

  /// Cells along x and y (0 when the world has no leaks).
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  double cellM() const { return h_; }
  /// Centre of cell (i, j), 0 <= i < nx(), 0 <= j < ny().
  Vec2 cellCentre(int i, int j) const { return {x0_ + (i + 0.5) * h_, y0_ + (j + 0.5) * h_}; }
  /// True when cell (i, j) is inside an obstacle.
  bool solid(int i, int j) const { return solid_[index(i, j)] != 0; }
  /// Largest stable explicit step, s (infinity without a grid).
  double maxStableStepS() const { return max_step_s_; }
  /// Sub-steps an advance by dt_s takes (64-bit: a jump of years of sim time
  /// at a millisecond step does not fit an int; capped at 2^62).
  std::int64_t substeps(double dt_s) const;

 private:
  // A leak as the grid sees it: its rate spread over up to four cells.
  struct Emitter {
    GasSource source;
    std::vector<std::pair<std::size_t, double>> cells;  // (padded index, weight); weights sum to 1
  };
  struct Field {
    std::vector<double> c;
    std::vector<Emitter> emitters;
    bool steady = true;  // c is the steady state of the leaks on now (see steady())
  };
  struct Stencil {
    std::array<std::size_t, 4> cell{};
    std::array<double, 4> weight{};
    int n = 0;
  };

  std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j + 1) * stride_ + static_cast<std::size_t>(i + 1);
  }
  void buildGrid(const World& world);
  bool blocked(Vec2 a, Vec2 b) const;
  bool inSolidCell(Vec2 p) const;
  Stencil stencil(Vec2 p) const;
  // One explicit step of c by dt_s; leaks active at t_s add their rate when `emit`.
  void step(std::vector<double>& c, const std::vector<Emitter>& emitters, double t_s, double dt_s, bool emit);
  // c = the field the emitter alone gives after `duration_s` on (from c), or off when !emit.
  void integrate(std::vector<double>& c, const Emitter& e, double duration_s, bool emit);
  // c = the emitter's steady state; false when SOR did not converge.
  bool solveSteady(std::vector<double>& c, const Emitter& e) const;
  // Adds the emitter's field at t = 0 to f; false unless that is its steady state (or nothing, for good).
  bool preIntegrate(Field& f, const Emitter& e);

  std::string file_;
  double d_m2_s_ = 0.0;
  double k_per_s_ = 0.0;
  Vec2 u_m_s_;
  double h_ = 0.1;
  int nx_ = 0;
  int ny_ = 0;
  std::size_t stride_ = 0;  // nx_ + 2: a ring of empty (c = 0) cells round the grid
  double x0_ = 0.0;         // lower-left corner of cell (0, 0)
  double y0_ = 0.0;
  double max_step_s_ = 0.0;
  std::vector<Segment> edges_;
  std::vector<uint8_t> solid_;
  std::vector<uint8_t> near_edge_;  // an edge passes within one cell: interpolation checks visibility
  std::vector<uint8_t> block_e_;    // face to the east neighbour blocked
  std::vector<uint8_t> block_n_;    // face to the north neighbour blocked
  // Per cell: rate (1/s) at which each neighbour's concentration flows in, and the total outflow + k.
  std::vector<double> in_e_, in_w_, in_n_, in_s_, out_;
  std::vector<double> scratch_;
  std::vector<std::string> gases_;
  std::vector<Field> fields_;
  double t_s_ = 0.0;
};

}  // namespace inspect::sim
