#pragma once
// A concentration map that grows as samples arrive (the live view's gas grid,
// docs/gas-maps.md): the same Nadaraya-Watson estimate as ConcentrationMap
// (value = sum w_i v_i / sum w_i, w_i = dt_i exp(-d^2 / 2h^2), kernel cut at
// 3.5 h, a density cut for "no data"), accumulated per sample instead of built
// from a whole run, so adding one costs a kernel's footprint, not the map.
// The grid starts around the first sample and grows in whole chunks. Pure.
#include <cstddef>
#include <vector>

#include "shared/gas/concentration_map.hpp"

namespace inspect::gas {

class LiveConcentrationMap {
 public:
  /// `options`: cell, bandwidth, density cuts and the longest time a sample
  /// stands for (as ConcentrationMap); `max_cells` bounds the grid (samples
  /// that would grow it further are not mapped, counted in outside()).
  explicit LiveConcentrationMap(const MapOptions& options = {}, double chunk_m = 4.0);

  /// Adds a reading (samples in time order; NaN values are skipped). Its
  /// weight is the time since the previous sample, capped at max_sample_dt_s.
  void add(const GasSample& s);

  bool empty() const { return cols_ == 0; }
  std::size_t cols() const { return cols_; }
  std::size_t rows() const { return rows_; }
  double cellM() const { return cell_m_; }
  /// Lower-left corner of cell (0, 0).
  double originX() const { return x0_; }
  double originY() const { return y0_; }
  /// Interpolated value; NaN where the density is below the cut.
  double value(std::size_t col, std::size_t row) const;
  /// 0 at the "no data" cut, 1 at full density.
  double coverage(std::size_t col, std::size_t row) const;
  std::size_t samples() const { return samples_; }
  std::size_t outside() const { return outside_; }

 private:
  /// Makes the grid cover [x0, x1] x [y0, y1] (whole chunks); false past max_cells.
  bool cover(double x_min, double y_min, double x_max, double y_max);

  MapOptions o_;
  double chunk_m_;
  double cell_m_;
  int reach_ = 0;                // kernel half-width in cells
  std::vector<double> kernel_;   // (2 reach + 1)^2 weights exp(-d^2 / 2h^2) for a sample at a cell centre
  double x0_ = 0, y0_ = 0;
  std::size_t cols_ = 0, rows_ = 0;
  std::vector<double> wsum_, wvsum_;
  double last_t_s_ = 0;
  bool have_last_ = false;
  std::size_t samples_ = 0, outside_ = 0;
};

}  // namespace inspect::gas
