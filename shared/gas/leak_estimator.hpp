#pragma once
// Where is the leak? A source-position estimate from one gas channel's raw
// readings along a recorded path (docs/gas-maps.md): a peaked plume model is
// pushed through the sensor's first-order lag along the path and fitted by
// least squares for candidate source positions; the residuals give a
// posterior over the position (mean, covariance, 95 % radius). Pure: no I/O.
#include <cstddef>
#include <string>
#include <vector>

#include "shared/gas/concentration_map.hpp"
#include "shared/geometry/segment.hpp"

namespace inspect::gas {


/// Parameters of estimateLeak (defaults as documented in docs/gas-maps.md).
struct LeakOptions {
  bool falling = false;                 // danger below background (O2): fit the deficit background - value
  std::vector<double> length_scales_m{0.4, 0.52, 0.68, 0.88, 1.14, 1.48, 1.92, 2.5};  // L of the shape K0(r / L)
  double source_radius_m = 0.15;        // r0 in K0(sqrt(r^2 + r0^2) / L): a source has a size
  double fit_rate_hz = 4.0;             // readings are averaged into bins at this rate for the fit
  double independent_rate_hz = 2.0;     // residuals count as independent at this rate (N_eff)
  double coarse_step_m = 0.3;           // first search grid
  std::size_t max_coarse_candidates = 6000;  // larger areas get a coarser first grid
  double fine_step_m = 0.05;            // refinement grid around the likely positions
  std::size_t max_fine_cells = 48;      // per side of the refinement grid
  double max_distance_m = 4.0;          // sources farther from every sample are not searched
  double model_error = 0.05;            // model misfit sd as a fraction of the modelled peak signal
  double min_snr = 3.0;                 // modelled peak signal along the path / sensor noise sd
  double min_likelihood_ratio = 25.0;   // (SSE_constant - SSE_min) / sigma^2 with N_eff
  double min_duration_s = 5.0;          // less data than this: not estimated
  double min_path_m = 1.0;              // a shorter path cannot locate anything
  double min_radius_m = 0.5;            // floor of radius95 (airflow skew, odometry drift, inlet offset)
  std::vector<geometry::Segment> walls;  // walls and obstacle edges (same frame as the samples): a candidate must be in line of sight of the path
  bool reflect_walls = false;           // walls reflect the plume: image sources (method of images)
  double image_max_m = 1.5;             // only walls this close to a candidate make an image
  // With walls (a site map): sources are searched only within this distance
  // of a wall or obstacle edge - leaks come from equipment (valves, flanges,
  // drains) on walls and benches. A single pass along a bench cannot tell a
  // leak on the bench from one on the far side of the path otherwise (the
  // bench reflects the plume, which then looks like a source further off).
  // 0 = anywhere. A leak in the open is then placed at the nearest surface.
  double surface_band_m = 0.6;
};

/// The estimate (frame of the samples).
struct LeakEstimate {
  bool found = false;
  std::string reason;             // not found: why; found: caveats ("" = none)
  double x_m = 0, y_m = 0;        // posterior mean of the source position
  double cov_xx_m2 = 0, cov_xy_m2 = 0, cov_yy_m2 = 0;  // posterior covariance
  double radius95_m = 0;          // circle about (x_m, y_m) holding 95 % of the posterior
  double best_x_m = 0, best_y_m = 0;  // least-squares best position
  double length_m = 0;            // best plume length scale L
  double amplitude = 0;           // A: model value at the source above background (deficit if falling)
  double background = 0;          // fitted clean-air value, channel units
  double peak_signal = 0;         // largest modelled reading above background along the path
  double noise_sd = 0;            // sensor noise sd (from successive differences)
  double snr = 0;                 // peak_signal / noise_sd
  double likelihood_ratio = 0;    // (SSE_constant - SSE_min) / sigma^2
  std::size_t samples = 0;        // usable readings
  double n_eff = 0;               // independent residuals assumed
  double search_step_m = 0;       // refinement grid step
  double rim_fraction = 0;        // posterior mass on the edge of the searched area
  bool split = false;             // the posterior has separate modes (its mean is unlikely itself)
};

/// Fits b + A f(|p - s| / L), A >= 0, pushed through the first-order lag
/// `tau_s` along the recorded path, to the raw readings, for candidate
/// sources s over `bounds` (within options.max_distance_m of the path); A and
/// b by linear least squares for each (s, L). `background` is the clean-air
/// value (used for falling channels, which fit background - value).
LeakEstimate estimateLeak(const std::vector<GasSample>& samples, double tau_s, double background,
                          const Bounds& bounds, const LeakOptions& options = {});

}  // namespace inspect::gas
