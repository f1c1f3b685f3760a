#include "shared/gas/live_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace inspect::gas {

LiveConcentrationMap::LiveConcentrationMap(const MapOptions& options, double chunk_m)
    : o_(options), chunk_m_(std::max(chunk_m, options.cell_m)), cell_m_(options.cell_m) {
  reach_ = static_cast<int>(std::ceil(3.5 * o_.bandwidth_m / cell_m_));
  const int n = 2 * reach_ + 1;
  kernel_.resize(static_cast<std::size_t>(n * n));
  const double h2 = 2.0 * o_.bandwidth_m * o_.bandwidth_m;
  for (int dy = -reach_; dy <= reach_; ++dy)
    for (int dx = -reach_; dx <= reach_; ++dx) {
      const double d2 = (dx * dx + dy * dy) * cell_m_ * cell_m_;
      kernel_[static_cast<std::size_t>((dy + reach_) * n + dx + reach_)] =
          d2 > 3.5 * 3.5 * o_.bandwidth_m * o_.bandwidth_m ? 0.0 : std::exp(-d2 / h2);
    }
}

bool LiveConcentrationMap::cover(double x_min, double y_min, double x_max, double y_max) {
  const auto snap_down = [&](double v) { return std::floor(v / chunk_m_) * chunk_m_; };
  const auto snap_up = [&](double v) { return std::ceil(v / chunk_m_) * chunk_m_; };
  if (cols_ > 0) {
    const double cx1 = x0_ + static_cast<double>(cols_) * cell_m_, cy1 = y0_ + static_cast<double>(rows_) * cell_m_;
    if (x_min >= x0_ && y_min >= y0_ && x_max <= cx1 && y_max <= cy1) return true;
    x_min = std::min(x_min, x0_);
    y_min = std::min(y_min, y0_);
    x_max = std::max(x_max, cx1);
    y_max = std::max(y_max, cy1);
  }
  const double nx0 = snap_down(x_min), ny0 = snap_down(y_min);
  const double wc = (snap_up(x_max) - nx0) / cell_m_, hc = (snap_up(y_max) - ny0) / cell_m_;
  // Each side first: far-off positions must not wrap the product round.
  const auto cap = static_cast<double>(o_.max_cells);
  if (!(wc >= 1 && hc >= 1) || wc > cap || hc > cap || wc * hc > cap) return false;
  const auto ncols = static_cast<std::size_t>(std::llround(wc));
  const auto nrows = static_cast<std::size_t>(std::llround(hc));
  std::vector<double> w(ncols * nrows, 0.0), wv(ncols * nrows, 0.0);
  if (cols_ > 0) {
    const auto ox = static_cast<std::size_t>(std::llround((x0_ - nx0) / cell_m_));
    const auto oy = static_cast<std::size_t>(std::llround((y0_ - ny0) / cell_m_));
    for (std::size_t r = 0; r < rows_; ++r)
      for (std::size_t c = 0; c < cols_; ++c) {
        w[(r + oy) * ncols + c + ox] = wsum_[r * cols_ + c];
        wv[(r + oy) * ncols + c + ox] = wvsum_[r * cols_ + c];
      }
  }
  x0_ = nx0;
  y0_ = ny0;
  cols_ = ncols;
  rows_ = nrows;
  wsum_ = std::move(w);
  wvsum_ = std::move(wv);
  return true;
}

void LiveConcentrationMap::add(const GasSample& s) {
  if (!std::isfinite(s.value) || !std::isfinite(s.x_m) || !std::isfinite(s.y_m)) return;
  const double dt = have_last_ ? std::clamp(s.t_s - last_t_s_, 0.0, o_.max_sample_dt_s) : 0.0;
  last_t_s_ = s.t_s;
  have_last_ = true;
  if (dt <= 0.0) return;
  const double r = reach_ * cell_m_;
  if (!cover(s.x_m - r, s.y_m - r, s.x_m + r, s.y_m + r)) {
    ++outside_;
    return;
  }
  ++samples_;
  // The nearest cell centre; the kernel table is exact at cell centres.
  const auto c0 = static_cast<long>(std::floor((s.x_m - x0_) / cell_m_));
  const auto r0 = static_cast<long>(std::floor((s.y_m - y0_) / cell_m_));
  const int n = 2 * reach_ + 1;
  for (int dy = -reach_; dy <= reach_; ++dy) {
    const long row = r0 + dy;
    if (row < 0 || row >= static_cast<long>(rows_)) continue;
    for (int dx = -reach_; dx <= reach_; ++dx) {
      const long col = c0 + dx;
      if (col < 0 || col >= static_cast<long>(cols_)) continue;
      const double k = kernel_[static_cast<std::size_t>((dy + reach_) * n + dx + reach_)];
      if (k == 0.0) continue;
      const std::size_t i = static_cast<std::size_t>(row) * cols_ + static_cast<std::size_t>(col);
      wsum_[i] += dt * k;
      wvsum_[i] += dt * k * s.value;
    }
  }
}

double LiveConcentrationMap::value(std::size_t col, std::size_t row) const {
  const std::size_t i = row * cols_ + col;
  if (wsum_[i] < o_.min_density_s || wsum_[i] <= 0.0) return std::numeric_limits<double>::quiet_NaN();
  return wvsum_[i] / wsum_[i];
}

double LiveConcentrationMap::coverage(std::size_t col, std::size_t row) const {
  const double d = wsum_[row * cols_ + col];
  const double full = std::max(o_.full_density_s, o_.min_density_s * 1.0001);
  return std::clamp((d - o_.min_density_s) / (full - o_.min_density_s), 0.0, 1.0);
}

}  // namespace inspect::gas
