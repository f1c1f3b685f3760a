#pragma once
// Concentration maps from the gas samples of a recorded run (docs/gas-maps.md):
// undoing the sensor's first-order lag, then a Nadaraya-Watson (Gaussian
// kernel) interpolation onto a grid, with a sample-density grid that says
// where the map has data. Pure: no I/O, no clock.
#include <cstddef>
#include <utility>
#include <vector>

namespace inspect::gas {

/// One reading of one gas channel where the sensor inlet was (any 2-D frame).
struct GasSample {
  double t_s = 0;    // time, s (increasing)
  double x_m = 0;    // inlet position
  double y_m = 0;
  double value = 0;  // reading in the channel's unit; NaN = no data (skipped)
};

/// An axis-aligned rectangle (map extent, leak search area).
struct Bounds {
  double x_min_m = 0, y_min_m = 0, x_max_m = 0, y_max_m = 0;
  bool valid() const { return x_max_m > x_min_m && y_max_m > y_min_m; }
  bool contains(double x_m, double y_m) const {
    return x_m >= x_min_m && x_m <= x_max_m && y_m >= y_min_m && y_m <= y_max_m;
  }
};

/// The bounding box of the samples' positions grown by `margin_m` (invalid when there are none).
Bounds boundsAround(const std::vector<GasSample>& samples, double margin_m);

/// How the lag is undone: c = y + tau dy/dt on a local-linear smoothed signal.
struct LagCompensationOptions {
  double window_s = 1.0;  // local linear fit over t +- window_s / 2 (smoothing vs noise gain)
  std::size_t min_samples = 3;  // fewer finite readings in the window: keep the raw value
};

/// Undoes a first-order sensor lag (time constant `tau_s` = t90 / ln 10):
/// each finite reading y(t) becomes y_s(t) + tau y_s'(t), where y_s, y_s' are
/// the value and slope of a least-squares line through the readings within
/// the window (inverse of tau y' + y = c). Positions and times are kept;
/// NaN readings stay NaN. tau_s <= 0 returns the samples unchanged.
std::vector<GasSample> compensateLag(const std::vector<GasSample>& samples, double tau_s,
                                     const LagCompensationOptions& options = {});

/// Grid and kernel of a ConcentrationMap.
struct MapOptions {
  double cell_m = 0.1;            // grid resolution
  double bandwidth_m = 0.45;      // Gaussian kernel standard deviation h
  double min_density_s = 0.15;    // below this (kernel-weighted seconds of samples): no data
  double full_density_s = 0.6;    // at or above: fully trusted (drawn unfaded)
  double max_sample_dt_s = 0.5;   // a sample stands for at most this long (gaps)
  std::size_t max_cells = 1'000'000;  // larger grids get coarser cells
};

/// A kernel-interpolated concentration grid over given bounds.
class ConcentrationMap {
 public:
  /// Where the map is highest (or lowest), among cells with data.
  struct Peak {
    bool valid = false;
    double x_m = 0, y_m = 0, value = 0;
  };

  /// Interpolates `samples` (already lag-compensated if wanted) onto a grid
  /// over `bounds`: value = sum w_i v_i / sum w_i with w_i = dt_i exp(-d^2 / 2h^2);
  /// density = sum w_i (seconds of samples, kernel-weighted).
  static ConcentrationMap build(const std::vector<GasSample>& samples, const Bounds& bounds,
                                const MapOptions& options = {});

  std::size_t cols() const { return cols_; }
  std::size_t rows() const { return rows_; }
  double cellM() const { return cell_m_; }
  const Bounds& bounds() const { return bounds_; }
  /// Centre of a cell.
  double cellX(std::size_t col) const { return bounds_.x_min_m + (static_cast<double>(col) + 0.5) * cell_m_; }
  double cellY(std::size_t row) const { return bounds_.y_min_m + (static_cast<double>(row) + 0.5) * cell_m_; }
  /// Interpolated value; NaN where there is no data (density below the cut).
  double value(std::size_t col, std::size_t row) const { return value_[row * cols_ + col]; }
  /// Sum of kernel weights (s).
  double density(std::size_t col, std::size_t row) const { return density_[row * cols_ + col]; }
  bool hasData(std::size_t col, std::size_t row) const { return density(col, row) >= min_density_s_; }
  /// 0 at the "no data" cut, 1 at full density (for fading poorly covered cells).
  double coverage(std::size_t col, std::size_t row) const;
  /// The highest cell (`lowest`: the lowest, for falling channels such as O2)
  /// among the cells a sample fell in (else among all cells with data).
  Peak peak(bool lowest = false) const;
  /// Range of the values over cells with data (NaN, NaN when none).
  std::pair<double, double> valueRange() const;

 private:
  Bounds bounds_;
  double cell_m_ = 0.1;
  std::size_t cols_ = 0, rows_ = 0;
  double min_density_s_ = 0, full_density_s_ = 1;
  std::vector<double> value_, density_;
  std::vector<char> visited_;  // a sample fell in the cell
};

}  // namespace inspect::gas
