#include "shared/gas/concentration_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace inspect::gas {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool usable(const GasSample& s) {
  return std::isfinite(s.t_s) && std::isfinite(s.x_m) && std::isfinite(s.y_m) && std::isfinite(s.value);
}

// One pass of a 1-D Gaussian convolution along rows (stride 1) or columns
// (stride = cols) of `grid`, truncated at `kernel.size() - 1` cells.
void convolve(std::vector<double>& grid, std::size_t cols, std::size_t rows, bool along_rows,
              const std::vector<double>& kernel) {
  const std::size_t n = along_rows ? cols : rows, lines = along_rows ? rows : cols;
  const std::size_t step = along_rows ? 1 : cols;
  const auto radius = static_cast<std::ptrdiff_t>(kernel.size()) - 1;
  std::vector<double> in(n);
  for (std::size_t l = 0; l < lines; ++l) {
    const std::size_t base = along_rows ? l * cols : l;
    bool any = false;
    for (std::size_t i = 0; i < n; ++i) {
      in[i] = grid[base + i * step];
      any = any || in[i] != 0.0;
    }
    if (!any) continue;  // most lines of a large map hold no samples
    for (std::size_t i = 0; i < n; ++i) {
      const auto ii = static_cast<std::ptrdiff_t>(i);
      const std::ptrdiff_t lo = std::max<std::ptrdiff_t>(0, ii - radius);
      const std::ptrdiff_t hi = std::min<std::ptrdiff_t>(static_cast<std::ptrdiff_t>(n) - 1, ii + radius);
      double sum = 0.0;
      for (std::ptrdiff_t j = lo; j <= hi; ++j) sum += kernel[static_cast<std::size_t>(std::abs(j - ii))] * in[j];
      grid[base + i * step] = sum;
    }
  }
}

}  // namespace

Bounds boundsAround(const std::vector<GasSample>& samples, double margin_m) {
  Bounds b{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
           -std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (const auto& s : samples) {
    if (!std::isfinite(s.x_m) || !std::isfinite(s.y_m)) continue;
    b.x_min_m = std::min(b.x_min_m, s.x_m);
    b.x_max_m = std::max(b.x_max_m, s.x_m);
    b.y_min_m = std::min(b.y_min_m, s.y_m);
    b.y_max_m = std::max(b.y_max_m, s.y_m);
  }
  if (!(b.x_min_m <= b.x_max_m)) return Bounds{};
  return {b.x_min_m - margin_m, b.y_min_m - margin_m, b.x_max_m + margin_m, b.y_max_m + margin_m};
}

std::vector<GasSample> compensateLag(const std::vector<GasSample>& samples, double tau_s,
                                     const LagCompensationOptions& options) {
  std::vector<GasSample> out = samples;
  if (!(tau_s > 0.0) || samples.empty()) return out;
  // Sliding sums over the finite readings within +- half a window; times are
  // taken from the first sample so that the sums keep their precision.
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < samples.size(); ++i)
    if (std::isfinite(samples[i].t_s) && std::isfinite(samples[i].value)) idx.push_back(i);
  if (idx.empty()) return out;
  const double t0 = samples[idx.front()].t_s, half = options.window_s / 2;
  double n = 0, st = 0, stt = 0, sy = 0, sty = 0;
  std::size_t lo = 0, hi = 0;  // window = idx[lo, hi)
  for (std::size_t k = 0; k < idx.size(); ++k) {
    const double tk = samples[idx[k]].t_s;
    while (hi < idx.size() && samples[idx[hi]].t_s <= tk + half) {
      const double t = samples[idx[hi]].t_s - t0, y = samples[idx[hi]].value;
      n += 1, st += t, stt += t * t, sy += y, sty += t * y;
      ++hi;
    }
    while (lo < hi && samples[idx[lo]].t_s < tk - half) {
      const double t = samples[idx[lo]].t_s - t0, y = samples[idx[lo]].value;
      n -= 1, st -= t, stt -= t * t, sy -= y, sty -= t * y;
      ++lo;
    }
    if (hi - lo < options.min_samples) continue;  // too sparse: keep the lagged reading
    const double var_t = stt - st * st / n;
    if (!(var_t > 1e-12)) continue;
    const double slope = (sty - st * sy / n) / var_t;
    const double t = tk - t0;
    const double smooth = sy / n + slope * (t - st / n);
    out[idx[k]].value = smooth + tau_s * slope;
  }
  return out;
}

ConcentrationMap ConcentrationMap::build(const std::vector<GasSample>& samples, const Bounds& bounds,
                                         const MapOptions& options) {
  ConcentrationMap m;
  m.bounds_ = bounds;
  m.min_density_s_ = options.min_density_s;
  m.full_density_s_ = std::max(options.full_density_s, options.min_density_s * 1.0001);
  if (!bounds.valid() || !(options.cell_m > 0.0) || !(options.bandwidth_m > 0.0)) return m;
  const double w = bounds.x_max_m - bounds.x_min_m, h = bounds.y_max_m - bounds.y_min_m;
  double cell = options.cell_m;
  if (w * h / (cell * cell) > static_cast<double>(options.max_cells))
    cell = std::sqrt(w * h / static_cast<double>(options.max_cells)) * 1.001;
  m.cell_m_ = cell;
  m.cols_ = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(w / cell - 1e-9)));
  m.rows_ = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(h / cell - 1e-9)));

  // Work on a grid padded by the kernel's reach so that samples just outside
  // the bounds still count; the kernel is truncated at 3.5 h.
  const auto pad = static_cast<std::size_t>(std::ceil(3.5 * options.bandwidth_m / cell));
  const std::size_t pc = m.cols_ + 2 * pad, pr = m.rows_ + 2 * pad;
  std::vector<double> wsum(pc * pr, 0.0), wvsum(pc * pr, 0.0);
  std::vector<char>& visited = m.visited_;
  visited.assign(m.cols_ * m.rows_, 0);
  const double x0 = bounds.x_min_m - static_cast<double>(pad) * cell;
  const double y0 = bounds.y_min_m - static_cast<double>(pad) * cell;

  // Each sample's weight is the time it stands for (half the gaps to its
  // neighbours, capped), so that a dwell counts by its duration and a change
  // of telemetry rate does not change the map. Splatting is bilinear onto the
  // four nearest cell centres, so the binning shifts nothing.
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < samples.size(); ++i)
    if (usable(samples[i])) idx.push_back(i);
  for (std::size_t k = 0; k < idx.size(); ++k) {
    const GasSample& s = samples[idx[k]];
    const double cap = options.max_sample_dt_s;
    const double prev = k > 0 ? std::min(s.t_s - samples[idx[k - 1]].t_s, cap) : 0.0;
    const double next = k + 1 < idx.size() ? std::min(samples[idx[k + 1]].t_s - s.t_s, cap) : 0.0;
    const double dt = idx.size() == 1 ? cap : 0.5 * (std::max(prev, 0.0) + std::max(next, 0.0));
    if (dt <= 0.0) continue;
    const double ux = (s.x_m - bounds.x_min_m) / cell, uy = (s.y_m - bounds.y_min_m) / cell;
    if (ux >= 0 && uy >= 0 && ux < static_cast<double>(m.cols_) && uy < static_cast<double>(m.rows_))
      visited[static_cast<std::size_t>(uy) * m.cols_ + static_cast<std::size_t>(ux)] = 1;
    const double fx = (s.x_m - x0) / cell - 0.5, fy = (s.y_m - y0) / cell - 0.5;
    if (fx < 0 || fy < 0 || fx >= static_cast<double>(pc - 1) || fy >= static_cast<double>(pr - 1)) continue;
    const auto cx = static_cast<std::size_t>(fx), cy = static_cast<std::size_t>(fy);
    const double ax = fx - static_cast<double>(cx), ay = fy - static_cast<double>(cy);
    const double wts[4] = {(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay};
    const std::size_t at[4] = {cy * pc + cx, cy * pc + cx + 1, (cy + 1) * pc + cx, (cy + 1) * pc + cx + 1};
    for (int j = 0; j < 4; ++j) {
      wsum[at[j]] += dt * wts[j];
      wvsum[at[j]] += dt * wts[j] * s.value;
    }
  }

  std::vector<double> kernel(pad + 1);
  for (std::size_t i = 0; i <= pad; ++i) {
    const double d = static_cast<double>(i) * cell / options.bandwidth_m;
    kernel[i] = std::exp(-0.5 * d * d);
  }
  for (auto* g : {&wsum, &wvsum}) {
    convolve(*g, pc, pr, true, kernel);
    convolve(*g, pc, pr, false, kernel);
  }

  m.value_.assign(m.cols_ * m.rows_, kNaN);
  m.density_.assign(m.cols_ * m.rows_, 0.0);
  for (std::size_t r = 0; r < m.rows_; ++r)
    for (std::size_t c = 0; c < m.cols_; ++c) {
      const std::size_t src = (r + pad) * pc + c + pad, dst = r * m.cols_ + c;
      m.density_[dst] = wsum[src];
      if (wsum[src] >= m.min_density_s_ && wsum[src] > 0.0) m.value_[dst] = wvsum[src] / wsum[src];
    }
  return m;
}

double ConcentrationMap::coverage(std::size_t col, std::size_t row) const {
  const double d = density(col, row);
  return std::clamp((d - min_density_s_) / (full_density_s_ - min_density_s_), 0.0, 1.0);
}

ConcentrationMap::Peak ConcentrationMap::peak(bool lowest) const {
  // Cells the path crossed first: off the path the kernel narrows along a
  // curved path and the value is less smoothed, not better known.
  for (const bool on_path : {true, false}) {
    Peak p;
    for (std::size_t r = 0; r < rows_; ++r)
      for (std::size_t c = 0; c < cols_; ++c) {
        const double v = value(c, r);
        if (!std::isfinite(v) || (on_path && !visited_[r * cols_ + c])) continue;
        if (!p.valid || (lowest ? v < p.value : v > p.value)) p = {true, cellX(c), cellY(r), v};
      }
    if (p.valid) return p;
  }
  return {};
}

std::pair<double, double> ConcentrationMap::valueRange() const {
  double lo = kNaN, hi = kNaN;
  for (double v : value_) {
    if (!std::isfinite(v)) continue;
    lo = std::isfinite(lo) ? std::min(lo, v) : v;
    hi = std::isfinite(hi) ? std::max(hi, v) : v;
  }
  return {lo, hi};
}

}  // namespace inspect::gas
