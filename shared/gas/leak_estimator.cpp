#include "shared/gas/leak_estimator.hpp"
#include "shared/util/number_text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

namespace inspect::gas {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kParams = 5;  // x, y, L, A, b

// Readings averaged over one fit bin (1 / fit_rate_hz).
struct Bin {
  double t_s, x_m, y_m, y;  // y: signal above background (deficit for falling channels)
};

// The plume shape f(r) = K0(sqrt(r^2 + r0^2) / L) / K0(r0 / L) tabulated in r
// (the steady state of 2-D diffusion with removal; K0 is costly to call).
struct Shape {
  double length_m = 1.0;
  double inv_step = 0.0;
  std::vector<double> f;

  Shape(double l_m, double r0_m) : length_m(l_m) {
    constexpr std::size_t kEntries = 2048;
    const double r_max = 8.0 * l_m, step = r_max / static_cast<double>(kEntries - 1);
    inv_step = 1.0 / step;
    const double norm = std::cyl_bessel_k(0.0, r0_m / l_m);
    f.resize(kEntries + 1);
    for (std::size_t i = 0; i < kEntries; ++i) {
      const double r = static_cast<double>(i) * step;
      f[i] = std::cyl_bessel_k(0.0, std::sqrt(r * r + r0_m * r0_m) / l_m) / norm;
    }
    f[kEntries - 1] = f[kEntries] = 0.0;  // beyond r_max the plume is taken as absent
  }
  double reach_m() const { return static_cast<double>(f.size() - 2) / inv_step; }
  double operator()(double r_m) const {
    const double x = r_m * inv_step;
    if (x >= static_cast<double>(f.size() - 2)) return 0.0;
    const auto i = static_cast<std::size_t>(x);
    const double a = x - static_cast<double>(i);
    return f[i] + a * (f[i + 1] - f[i]);
  }
};

// Result of the linear fit at one (s, L).
struct Fit {
  double sse = kInf, a = 0, b = 0, z_max = 0;
};

// The forward model along the binned path and the linear fit of A and b.
class Model {
 public:
  Model(std::vector<Bin> bins, double tau_s, const LeakOptions& o)
      : bins_(std::move(bins)), walls_(o.reflect_walls ? o.walls : std::vector<geometry::Segment>{}),
        image_max_m_(o.image_max_m) {
    for (double l : o.length_scales_m)
      if (l > 0.0) shapes_.emplace_back(l, std::max(o.source_radius_m, 1e-3));
    decay_.resize(bins_.size(), 0.0);
    for (std::size_t k = 1; k < bins_.size(); ++k)
      decay_[k] = tau_s > 0.0 ? std::exp(-(bins_[k].t_s - bins_[k - 1].t_s) / tau_s) : 0.0;
    const double n = static_cast<double>(bins_.size());
    for (const auto& b : bins_) sy_ += b.y, syy_ += b.y * b.y;
    sse0_ = std::max(0.0, syy_ - sy_ * sy_ / n);
    r_.resize(bins_.size());
    for (const auto& sh : shapes_) reach_m_ = std::max(reach_m_, sh.reach_m());
  }
  double sse0() const { return sse0_; }
  std::size_t shapes() const { return shapes_.size(); }
  double length(std::size_t l) const { return shapes_[l].length_m; }

  // Image sources of (sx, sy) in the walls and obstacle edges near it: a
  // wall does not let gas through, so near one the plume is as if a mirror
  // source stood behind it (method of images, first order; only for walls
  // whose foot point from the source lies on the wall, within image_max_m).
  // They make a source beside a bench look different from its mirror image
  // across the robot's path, which a free-space plume cannot tell apart.
  void images(double sx, double sy) {
    img_.clear();
    for (const auto& w : walls_) {
      const double ux = w.b.x - w.a.x, uy = w.b.y - w.a.y, len2 = ux * ux + uy * uy;
      if (len2 < 1e-12) continue;
      const double t = ((sx - w.a.x) * ux + (sy - w.a.y) * uy) / len2;
      if (t < 0.0 || t > 1.0) continue;
      const double fx = w.a.x + t * ux, fy = w.a.y + t * uy;
      const double h = std::hypot(sx - fx, sy - fy);
      if (h < 1e-6 || h > image_max_m_) continue;
      img_.push_back({2.0 * fx - sx, 2.0 * fy - sy});
      if (img_.size() == kMaxImages) break;
    }
  }

  // Fits every L for a source at (sx, sy); out[l] per shape.
  void fit(double sx, double sy, std::vector<Fit>& out) {
    const std::size_t n = bins_.size();
    images(sx, sy);
    const std::size_t ni = img_.size();
    ri_.resize(ni * n);
    // Distances, and for each bin the next one within any shape's reach: on a
    // long path most bins see nothing of a candidate, and once the sensor has
    // settled back (z ~ 0) they add nothing to the sums and can be skipped.
    next_near_.resize(n + 1);
    next_near_[n] = n;
    for (std::size_t k = n; k-- > 0;) {  // (not std::hypot: this is the hot loop)
      const double dx = bins_[k].x_m - sx, dy = bins_[k].y_m - sy;
      r_[k] = std::sqrt(dx * dx + dy * dy);
      double nearest = r_[k];
      for (std::size_t i = 0; i < ni; ++i) {
        const double ix = bins_[k].x_m - img_[i].first, iy = bins_[k].y_m - img_[i].second;
        ri_[i * n + k] = std::sqrt(ix * ix + iy * iy);
        nearest = std::min(nearest, ri_[i * n + k]);
      }
      next_near_[k] = nearest < reach_m_ ? k : next_near_[k + 1];
    }
    const auto shape = [&](const Shape& sh, std::size_t k) {
      double u = sh(r_[k]);
      for (std::size_t i = 0; i < ni; ++i) u += sh(ri_[i * n + k]);
      return u;
    };
    out.resize(shapes_.size());
    // Shapes in blocks of kBlock run side by side: independent filter chains
    // keep the pipeline busy where one chain would wait on itself.
    constexpr std::size_t kBlock = 4;
    for (std::size_t l0 = 0; l0 < shapes_.size(); l0 += kBlock) {
      const std::size_t m = std::min(kBlock, shapes_.size() - l0);
      const Shape* sh[kBlock];
      // The sensor sees the plume through its lag (exact for an input linear
      // between bins); the sensor starts settled on what it first sees.
      double u_prev[kBlock] = {}, z[kBlock] = {}, sz[kBlock] = {}, szz[kBlock] = {}, syz[kBlock] = {}, z_max[kBlock] = {};
      for (std::size_t j = 0; j < m; ++j) {
        sh[j] = &shapes_[l0 + j];
        u_prev[j] = z[j] = shape(*sh[j], 0);
      }
      for (std::size_t k = 0; k < n; ++k) {
        if (next_near_[k] != k) {  // out of reach: once every chain has settled, jump to the next bin in reach
          bool settled = true;
          for (std::size_t j = 0; j < m; ++j) settled = settled && u_prev[j] == 0.0 && z[j] <= 1e-7 * z_max[j];
          if (settled) {
            k = next_near_[k];
            if (k == n) break;
            for (std::size_t j = 0; j < m; ++j) z[j] = 0.0;
          }
        }
        const double a = decay_[k], y = bins_[k].y;
        for (std::size_t j = 0; j < m; ++j) {
          const double u = shape(*sh[j], k);
          if (k) z[j] = a * z[j] + (1.0 - a) * 0.5 * (u + u_prev[j]);
          u_prev[j] = u;
          sz[j] += z[j], szz[j] += z[j] * z[j], syz[j] += z[j] * y;
          z_max[j] = std::max(z_max[j], z[j]);
        }
      }
      for (std::size_t j = 0; j < m; ++j) out[l0 + j] = linearFit(sz[j], szz[j], syz[j], z_max[j]);
    }
  }

  // A and b by least squares from the sums over the bins, A >= 0.
  Fit linearFit(double sz, double szz, double syz, double z_max) const {
    const double nn = static_cast<double>(bins_.size());
    const double szz_c = szz - sz * sz / nn, syz_c = syz - sz * sy_ / nn;
    Fit f;
    f.z_max = z_max;
    if (szz_c > 1e-15 && syz_c > 0.0) {
      f.a = syz_c / szz_c;
      f.b = (sy_ - f.a * sz) / nn;
      f.sse = std::max(0.0, sse0_ - syz_c * syz_c / szz_c);
    } else {  // A >= 0: no plume explains these readings better than a constant
      f.a = 0.0;
      f.b = sy_ / nn;
      f.sse = sse0_;
    }
    return f;
  }

 private:
  std::vector<Bin> bins_;
  std::vector<Shape> shapes_;
  std::vector<double> decay_, r_;
  static constexpr std::size_t kMaxImages = 4;
  std::vector<geometry::Segment> walls_;
  double image_max_m_ = 1.5;
  std::vector<std::pair<double, double>> img_;
  std::vector<double> ri_;  // distances of the bins to each image, image-major
  std::vector<std::size_t> next_near_;
  double reach_m_ = 0, sy_ = 0, syy_ = 0, sse0_ = 0;
};

// Readings averaged over consecutive windows of 1 / rate (noise down, cost down).
std::vector<Bin> binSamples(const std::vector<GasSample>& s, double rate_hz, double sign, double background) {
  std::vector<Bin> bins;
  const double dt = 1.0 / rate_hz;
  std::size_t i = 0;
  while (i < s.size()) {
    const double start = s[i].t_s;
    Bin b{0, 0, 0, 0};
    double n = 0;
    for (; i < s.size() && s[i].t_s < start + dt; ++i, n += 1) {
      b.t_s += s[i].t_s, b.x_m += s[i].x_m, b.y_m += s[i].y_m, b.y += sign * (s[i].value - background);
    }
    bins.push_back({b.t_s / n, b.x_m / n, b.y_m / n, b.y / n});
  }
  return bins;
}

// Sensor noise sd from successive differences (robust: MAD), which a slow
// plume signal hardly enters at telemetry rates.
double noiseSd(const std::vector<GasSample>& s) {
  std::vector<double> d;
  for (std::size_t i = 1; i < s.size(); ++i)
    if (s[i].t_s - s[i - 1].t_s <= 1.0) d.push_back(std::abs(s[i].value - s[i - 1].value));
  if (d.empty()) return 0.0;
  auto mid = d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2);
  std::nth_element(d.begin(), mid, d.end());
  return 1.4826 * *mid / std::sqrt(2.0);
}

// A number for a message: 3 significant digits.
std::string num(double v) { return util::significant(v, 3); }

// Which candidate positions may hold the source: inside the bounds, within
// reach of the path, and (with walls) in line of sight of one of the nearest
// path points - a plume does not pass through walls.
class SearchArea {
 public:
  SearchArea(const std::vector<Bin>& bins, const Bounds& bounds, const LeakOptions& o)
      : bounds_(bounds), reach_m_(o.max_distance_m), band_m_(o.surface_band_m), walls_(o.walls) {
    for (const auto& b : bins)  // the path thinned to ~0.2 m spacing
      if (path_.empty() || std::hypot(b.x_m - path_.back().first, b.y_m - path_.back().second) >= 0.2)
        path_.emplace_back(b.x_m, b.y_m);
  }
  bool allowed(double x, double y) const {
    if (!bounds_.contains(x, y)) return false;
    near_.clear();
    for (const auto& [px, py] : path_) {
      const double d2 = (px - x) * (px - x) + (py - y) * (py - y);
      if (d2 <= reach_m_ * reach_m_) near_.emplace_back(d2, std::make_pair(px, py));
    }
    if (near_.empty()) return false;
    if (walls_.empty()) return true;
    if (band_m_ > 0.0 && std::none_of(walls_.begin(), walls_.end(), [&](const geometry::Segment& w) {
          return geometry::pointSegmentDistance({x, y}, w) <= band_m_;
        }))
      return false;
    const std::size_t n = std::min<std::size_t>(12, near_.size());
    std::partial_sort(near_.begin(), near_.begin() + static_cast<std::ptrdiff_t>(n), near_.end());
    for (std::size_t i = 0; i < n; ++i) {
      // Not a structured binding: clang 14 cannot capture one in the lambda below.
      const double px = near_[i].second.first, py = near_[i].second.second;
      if (std::none_of(walls_.begin(), walls_.end(), [&](const geometry::Segment& w) { return geometry::segmentsCross({{x, y}, {px, py}}, w); }))
        return true;
    }
    return false;
  }
  // Largest angle (rad) between the bearings from (x, y) to the path points
  // within reach: more than pi = the path passed on one side only.
  double bearingGap(double x, double y) const {
    std::vector<double> a;
    for (const auto& [px, py] : path_)
      if (std::hypot(px - x, py - y) <= reach_m_) a.push_back(std::atan2(py - y, px - x));
    if (a.size() < 2) return 2 * std::numbers::pi;
    std::sort(a.begin(), a.end());
    double gap = a.front() + 2 * std::numbers::pi - a.back();
    for (std::size_t i = 1; i < a.size(); ++i) gap = std::max(gap, a[i] - a[i - 1]);
    return gap;
  }

 private:
  Bounds bounds_;
  double reach_m_;
  double band_m_;
  std::vector<geometry::Segment> walls_;
  std::vector<std::pair<double, double>> path_;
  mutable std::vector<std::pair<double, std::pair<double, double>>> near_;
};

// One searched grid: cell centres, their best SSE over L (and which L), and
// the posterior weight summed over L.
struct Grid {
  double x0 = 0, y0 = 0, step = 0;
  std::size_t nx = 0, ny = 0;
  std::vector<char> allowed;
  std::vector<std::vector<Fit>> fits;  // per cell, per L (empty when not allowed)
  bool anyAllowed() const { return std::find(allowed.begin(), allowed.end(), 1) != allowed.end(); }
  double x(std::size_t i) const { return x0 + static_cast<double>(i) * step; }
  double y(std::size_t j) const { return y0 + static_cast<double>(j) * step; }
};

Grid searchGrid(Model& model, const SearchArea& area, double x0, double y0, double step, std::size_t nx,
                std::size_t ny) {
  Grid g{x0, y0, step, nx, ny, {}, {}};
  g.allowed.assign(nx * ny, 0);
  g.fits.resize(nx * ny);
  for (std::size_t j = 0; j < ny; ++j)
    for (std::size_t i = 0; i < nx; ++i) {
      if (!area.allowed(g.x(i), g.y(j))) continue;
      g.allowed[j * nx + i] = 1;
      model.fit(g.x(i), g.y(j), g.fits[j * nx + i]);
    }
  return g;
}

// The best (s, L) of a grid.
struct Best {
  Fit fit;
  double x_m = 0, y_m = 0;
  std::size_t shape = 0;
};

Best bestOf(const Grid& g) {
  Best b;
  for (std::size_t c = 0; c < g.fits.size(); ++c)
    for (std::size_t l = 0; l < g.fits[c].size(); ++l)
      if (g.fits[c][l].sse < b.fit.sse) b = {g.fits[c][l], g.x(c % g.nx), g.y(c / g.nx), l};
  return b;
}

// log of the posterior weight of each cell (summed over L), relative to sse_min.
std::vector<double> logWeights(const Grid& g, double sse_min, double sigma2) {
  std::vector<double> lw(g.fits.size(), -kInf);
  for (std::size_t c = 0; c < g.fits.size(); ++c) {
    if (g.fits[c].empty()) continue;
    double w = 0.0;
    for (const auto& f : g.fits[c]) w += std::exp(-(f.sse - sse_min) / (2.0 * sigma2));
    if (w > 0.0) lw[c] = std::log(w);
  }
  return lw;
}

// Mean, covariance and 95 % radius of the position posterior over a grid's
// cells (equal areas; L marginalised), the mass on the rim of the searched
// area, and whether the posterior at its own mean is low (separate modes).
struct Posterior {
  double x_m = 0, y_m = 0, cxx = 0, cxy = 0, cyy = 0, r95_m = 0, rim = 0;
  bool split = false;
};

Posterior posteriorOf(const Grid& g, double sse_min, double sigma2, const SearchArea& area) {
  Posterior p;
  const auto lw = logWeights(g, sse_min, sigma2);
  const double lmax = *std::max_element(lw.begin(), lw.end());
  std::vector<double> wt(lw.size(), 0.0);
  double wsum = 0;
  for (std::size_t c = 0; c < lw.size(); ++c) {
    if (!std::isfinite(lw[c])) continue;
    wt[c] = std::exp(lw[c] - lmax);
    wsum += wt[c];
    p.x_m += wt[c] * g.x(c % g.nx);
    p.y_m += wt[c] * g.y(c / g.nx);
  }
  p.x_m /= wsum, p.y_m /= wsum;
  std::vector<std::pair<double, double>> by_dist;  // distance from the mean, weight
  const double step = g.step;
  for (std::size_t c = 0; c < wt.size(); ++c) {
    if (wt[c] <= 0.0) continue;
    const double x = g.x(c % g.nx), y = g.y(c / g.nx), dx = x - p.x_m, dy = y - p.y_m;
    p.cxx += wt[c] * dx * dx, p.cxy += wt[c] * dx * dy, p.cyy += wt[c] * dy * dy;
    by_dist.emplace_back(std::hypot(dx, dy), wt[c]);
    if (wt[c] >= 1e-6 && (!area.allowed(x - step, y) || !area.allowed(x + step, y) || !area.allowed(x, y - step) ||
                          !area.allowed(x, y + step)))
      p.rim += wt[c];
  }
  const double cell_var = step * step / 12.0;  // the grid's own resolution
  p.cxx = p.cxx / wsum + cell_var, p.cxy /= wsum, p.cyy = p.cyy / wsum + cell_var;
  p.rim /= wsum;
  std::sort(by_dist.begin(), by_dist.end());
  double acc = 0;
  for (const auto& [d, wc] : by_dist) {
    acc += wc;
    p.r95_m = d + 0.5 * step;
    if (acc >= 0.95 * wsum) break;
  }
  const auto i = static_cast<std::size_t>(std::clamp(std::round((p.x_m - g.x0) / step), 0.0, static_cast<double>(g.nx - 1)));
  const auto j = static_cast<std::size_t>(std::clamp(std::round((p.y_m - g.y0) / step), 0.0, static_cast<double>(g.ny - 1)));
  p.split = wt[j * g.nx + i] < 0.01;
  return p;
}

// The samples with finite numbers, in time order.
std::vector<GasSample> finiteSortedSamples(const std::vector<GasSample>& samples) {
  std::vector<GasSample> s;
  s.reserve(samples.size());
  for (const auto& x : samples)
    if (std::isfinite(x.t_s) && std::isfinite(x.x_m) && std::isfinite(x.y_m) && std::isfinite(x.value)) s.push_back(x);
  std::stable_sort(s.begin(), s.end(), [](const GasSample& a, const GasSample& b) { return a.t_s < b.t_s; });
  return s;
}

// Residuals closer in time than 1 / independent_rate_hz are correlated
// (sensor lag, plume meander): one counts per such slot.
double independentBins(const std::vector<Bin>& bins, double t0_s, double independent_rate_hz) {
  std::vector<long long> slots;
  for (const auto& b : bins) slots.push_back(static_cast<long long>(std::floor((b.t_s - t0_s) * independent_rate_hz)));
  return static_cast<double>(std::unique(slots.begin(), slots.end()) - slots.begin());
}

// The refinement: a fine grid over every coarse cell that is not negligible
// (log weight lw above 1e-4 of the best), one coarse step around them.
Grid fineGridAround(Model& model, const SearchArea& area, const Grid& cg, const std::vector<double>& lw,
                    const LeakOptions& o) {
  const double coarse = cg.step;
  double lo_x = kInf, lo_y = kInf, hi_x = -kInf, hi_y = -kInf;
  for (std::size_t j = 0; j < cg.ny; ++j)
    for (std::size_t i = 0; i < cg.nx; ++i)
      if (lw[j * cg.nx + i] > std::log(1e-4)) {
        lo_x = std::min(lo_x, cg.x(i)), hi_x = std::max(hi_x, cg.x(i));
        lo_y = std::min(lo_y, cg.y(j)), hi_y = std::max(hi_y, cg.y(j));
      }
  lo_x -= coarse, lo_y -= coarse, hi_x += coarse, hi_y += coarse;
  const double span = std::max(hi_x - lo_x, hi_y - lo_y);
  const double fine = std::max(o.fine_step_m, span / static_cast<double>(std::max<std::size_t>(o.max_fine_cells, 2)));
  const auto fnx = static_cast<std::size_t>(std::floor((hi_x - lo_x) / fine)) + 1;
  const auto fny = static_cast<std::size_t>(std::floor((hi_y - lo_y) / fine)) + 1;
  return searchGrid(model, area, lo_x, lo_y, fine, fnx, fny);
}

// What a found estimate's reader should know: "" or caveats joined by "; ".
std::string leakCaveats(const LeakEstimate& e, const SearchArea& area) {
  std::vector<std::string> caveats;
  if (e.rim_fraction > 0.05) caveats.push_back("the estimate reaches the edge of the searched area: the source may lie beyond it");
  if (e.split)
    caveats.push_back("the likely positions fall apart (e.g. either side of a straight pass): the circle holds them all");
  else if (area.bearingGap(e.x_m, e.y_m) > std::numbers::pi + 0.2)
    caveats.push_back("seen from one side only: the distance from the path rests on the plume-shape model (a pass on "
                      "the other side pins it)");
  std::string out;
  for (const auto& c : caveats) out += (out.empty() ? "" : "; ") + c;
  return out;
}

}  // namespace

LeakEstimate estimateLeak(const std::vector<GasSample>& samples, double tau_s, double background,
                          const Bounds& bounds, const LeakOptions& o) {
  LeakEstimate e;
  const std::vector<GasSample> s = finiteSortedSamples(samples);
  e.samples = s.size();
  e.noise_sd = noiseSd(s);
  if (!std::isfinite(background)) background = 0.0;
  if (!bounds.valid()) {
    e.reason = "no search area";
    return e;
  }
  if (s.size() < 10 || s.back().t_s - s.front().t_s < o.min_duration_s) {
    e.reason = "too few samples (" + std::to_string(s.size()) + ")";
    return e;
  }
  double path_m = 0.0;
  for (std::size_t i = 1; i < s.size(); ++i) path_m += std::hypot(s[i].x_m - s[i - 1].x_m, s[i].y_m - s[i - 1].y_m);
  if (path_m < o.min_path_m) {
    e.reason = "the path is too short to locate a source";
    return e;
  }

  const double sign = o.falling ? -1.0 : 1.0;
  std::vector<Bin> bins = binSamples(s, o.fit_rate_hz, sign, background);
  e.n_eff = independentBins(bins, s.front().t_s, o.independent_rate_hz);
  if (e.n_eff < 2.0 * kParams + 5.0) {
    e.reason = "too few independent samples";
    return e;
  }
  const auto n_bins = static_cast<double>(bins.size());
  const double per_bin = static_cast<double>(s.size()) / n_bins;
  const SearchArea area(bins, bounds, o);
  Model model(std::move(bins), tau_s, o);
  if (model.shapes() == 0) {
    e.reason = "no plume length scales";
    return e;
  }
  if (!(model.sse0() > 0.0)) {
    e.reason = "the readings do not vary";
    return e;
  }

  // Coarse search over the bounds.
  const double w = bounds.x_max_m - bounds.x_min_m, h = bounds.y_max_m - bounds.y_min_m;
  const double coarse = std::max(o.coarse_step_m, std::sqrt(w * h / static_cast<double>(std::max<std::size_t>(o.max_coarse_candidates, 1))));
  const auto cnx = static_cast<std::size_t>(std::ceil(w / coarse)), cny = static_cast<std::size_t>(std::ceil(h / coarse));
  const Grid cg = searchGrid(model, area, bounds.x_min_m + 0.5 * (w - static_cast<double>(cnx - 1) * coarse),
                             bounds.y_min_m + 0.5 * (h - static_cast<double>(cny - 1) * coarse), coarse, cnx, cny);
  Best best = bestOf(cg);
  if (!std::isfinite(best.fit.sse)) {
    e.reason = "no candidate position within " + num(o.max_distance_m) + " m of the path";
    return e;
  }
  // sigma^2 = SSE_min / (N_eff - p), never below what the sensor noise alone
  // leaves, plus the model's own error (a real plume is not exactly K0-shaped):
  // model_error x the modelled peak signal, as sd of a bin.
  const double inflate = n_bins / e.n_eff;
  const double noise_floor = e.noise_sd * e.noise_sd / per_bin * inflate;
  auto sigma2Of = [&](const Best& b) {
    const double model_sd = o.model_error * b.fit.a * b.fit.z_max;
    return std::max({b.fit.sse / (e.n_eff - kParams), noise_floor, 1e-12 * model.sse0() + 1e-300}) +
           model_sd * model_sd * inflate;
  };

  // Refine around every coarse cell that is not negligible.
  const Grid fg = fineGridAround(model, area, cg, logWeights(cg, best.fit.sse, sigma2Of(best)), o);
  const double fine = fg.step;
  if (const Best fb = bestOf(fg); fb.fit.sse < best.fit.sse) best = fb;
  const double sigma2 = sigma2Of(best);
  e.search_step_m = fine;
  e.likelihood_ratio = (model.sse0() - best.fit.sse) / sigma2;
  e.best_x_m = best.x_m, e.best_y_m = best.y_m, e.length_m = model.length(best.shape);
  e.amplitude = best.fit.a;
  e.background = background + sign * best.fit.b;
  e.peak_signal = best.fit.a * best.fit.z_max;

  // The posterior on the refinement grid (on the coarse one should no fine
  // cell be allowed).
  const Posterior post = posteriorOf(fg.anyAllowed() ? fg : cg, best.fit.sse, sigma2, area);
  e.x_m = post.x_m, e.y_m = post.y_m;
  e.cov_xx_m2 = post.cxx, e.cov_xy_m2 = post.cxy, e.cov_yy_m2 = post.cyy;
  e.radius95_m = std::max(o.min_radius_m, post.r95_m);
  e.rim_fraction = post.rim;
  e.split = post.split;

  e.snr = e.noise_sd > 0.0 ? e.peak_signal / e.noise_sd : (e.peak_signal > 0.0 ? kInf : 0.0);
  if (!(e.peak_signal > 0.0) || e.snr < o.min_snr) {
    e.reason = "no plume above the noise (modelled peak " + num(e.peak_signal) + " < " + num(o.min_snr) +
               " x noise sd " + num(e.noise_sd) + ")";
    return e;
  }
  if (e.likelihood_ratio < o.min_likelihood_ratio) {
    e.reason = "a plume does not explain the readings significantly better than a constant";
    return e;
  }
  e.found = true;
  e.reason = leakCaveats(e, area);
  return e;
}

}  // namespace inspect::gas
