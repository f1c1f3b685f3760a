#include "sim/gas_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include "shared/config/config_node.hpp"

namespace inspect::sim {
namespace {

// SOR: stop when the largest update is this small relative to the largest value.
constexpr double kSteadyTolerance = 1e-10;
constexpr int kMaxSweeps = 5000;
// Sub-step start times carry rounding: a leak due at 5 s starts with the sub-step at 4.999999999 s.
constexpr double kTimeSlack_s = 1e-9;

bool boxesOverlap(const Segment& a, const Segment& b) {
  return std::max(a.a.x, a.b.x) >= std::min(b.a.x, b.b.x) &&
         std::max(b.a.x, b.b.x) >= std::min(a.a.x, a.b.x) &&
         std::max(a.a.y, a.b.y) >= std::min(b.a.y, b.b.y) &&
         std::max(b.a.y, b.b.y) >= std::min(a.a.y, a.b.y);
}

}  // namespace

GasModel::GasModel(const World& world)
    : file_(world.source_file),
      d_m2_s_(world.gas.diffusivity_m2_s),
      k_per_s_(world.gas.ventilation_per_s),
      u_m_s_(world.gas.airflow_m_s),
      h_(world.gas.cell_m),
      max_step_s_(std::numeric_limits<double>::infinity()) {
  if (world.gas.sources.empty()) return;
  buildGrid(world);

  for (std::size_t i = 0; i < world.gas.sources.size(); ++i) {
    const GasSource& s = world.gas.sources[i];
    if (field(s.gas) < 0) {
      gases_.push_back(s.gas);
      fields_.push_back({std::vector<double>(out_.size(), 0.0), {}});
    }
    const Stencil st = stencil(s.position);
    if (st.n == 0) {
      std::ostringstream os;
      os << file_ << ": gas.sources[" << i << "]: no free grid cell is reachable from the leak at (" << s.position.x
         << ", " << s.position.y << ") without crossing a wall; move it or use a smaller gas.cell_m";
      throw config::ConfigError(os.str());
    }
    Emitter e{s, {}};
    for (std::size_t k = 0; k < static_cast<std::size_t>(st.n); ++k) e.cells.emplace_back(st.cell[k], st.weight[k]);
    Field& f = fields_[static_cast<std::size_t>(field(s.gas))];
    f.steady = preIntegrate(f, e) && f.steady;
    f.emitters.push_back(std::move(e));
  }
}

void GasModel::buildGrid(const World& world) {
  const auto box = solidBounds(world);
  if (!box) throw config::ConfigError(file_ + ": gas.sources: a world with leaks needs walls or obstacles");
  for (const auto& w : world.walls) edges_.push_back(w);
  for (const auto& o : world.obstacles)
    for (const auto& e : geometry::edgesOf(o.polygon)) edges_.push_back(e);

  // Cell faces on multiples of h: walls on round coordinates then lie on faces.
  const double m = std::max(kMargin_m, 2.0 * h_);
  x0_ = h_ * std::floor((box->lo.x - m) / h_);
  y0_ = h_ * std::floor((box->lo.y - m) / h_);
  nx_ = static_cast<int>(std::lround((h_ * std::ceil((box->hi.x + m) / h_) - x0_) / h_));
  ny_ = static_cast<int>(std::lround((h_ * std::ceil((box->hi.y + m) / h_) - y0_) / h_));
  const double cells = static_cast<double>(nx_) * static_cast<double>(ny_);
  if (cells > static_cast<double>(kMaxCells)) {
    std::ostringstream os;
    os << file_ << ": gas.cell_m: the gas grid over the walls' bounding box would have " << nx_ << " x " << ny_
       << " cells (limit " << kMaxCells << "); use larger cells";
    throw config::ConfigError(os.str());
  }
  // Positivity (every coefficient of the explicit update >= 0) bounds the step.
  max_step_s_ = 1.0 / (4.0 * d_m2_s_ / (h_ * h_) + (std::abs(u_m_s_.x) + std::abs(u_m_s_.y)) / h_ + k_per_s_);
  std::vector<std::string> gases;
  for (const auto& s : world.gas.sources)
    if (std::find(gases.begin(), gases.end(), s.gas) == gases.end()) gases.push_back(s.gas);
  const double work = static_cast<double>(gases.size()) * cells / (kStabilityFactor * max_step_s_);
  if (work > kMaxCellUpdatesPerSimS) {
    std::ostringstream os;
    os << file_ << ": gas.cell_m: " << nx_ << " x " << ny_ << " cells with sub-steps of "
       << kStabilityFactor * max_step_s_ << " s would need " << work << " cell updates per second of sim time (limit "
       << kMaxCellUpdatesPerSimS << "); use larger cells or a smaller diffusivity_m2_s";
    throw config::ConfigError(os.str());
  }
  stride_ = static_cast<std::size_t>(nx_) + 2;
  const std::size_t total = stride_ * (static_cast<std::size_t>(ny_) + 2);
  solid_.assign(total, 0);
  near_edge_.assign(total, 0);
  block_e_.assign(total, 0);
  block_n_.assign(total, 0);

  auto rangeOf = [&](double lo, double hi, double origin, int n) {
    const int a = std::max(-1, static_cast<int>(std::floor((lo - origin) / h_ - 0.5)));
    const int b = std::min(n, static_cast<int>(std::ceil((hi - origin) / h_ - 0.5)));
    return std::pair{a, b};
  };
  for (const auto& o : world.obstacles) {
    double lx = 1e300, ly = 1e300, hx = -1e300, hy = -1e300;
    for (const auto& v : o.polygon.vertices) {
      lx = std::min(lx, v.x), ly = std::min(ly, v.y), hx = std::max(hx, v.x), hy = std::max(hy, v.y);
    }
    const auto [i0, i1] = rangeOf(lx, hx, x0_, nx_ - 1);
    const auto [j0, j1] = rangeOf(ly, hy, y0_, ny_ - 1);
    for (int j = std::max(j0, 0); j <= j1; ++j)
      for (int i = std::max(i0, 0); i <= i1; ++i)
        if (geometry::pointInPolygon(cellCentre(i, j), o.polygon)) solid_[index(i, j)] = 1;
  }
  // Faces whose centre-to-centre segment crosses an edge: only cells near each edge can have one.
  for (const auto& e : edges_) {
    const auto [i0, i1] = rangeOf(std::min(e.a.x, e.b.x) - h_, std::max(e.a.x, e.b.x) + h_, x0_, nx_);
    const auto [j0, j1] = rangeOf(std::min(e.a.y, e.b.y) - h_, std::max(e.a.y, e.b.y) + h_, y0_, ny_);
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        const std::size_t idx = index(i, j);
        near_edge_[idx] = 1;
        const Vec2 c = cellCentre(i, j);
        if (i < nx_ && geometry::segmentsIntersect({c, cellCentre(i + 1, j)}, e)) block_e_[idx] = 1;
        if (j < ny_ && geometry::segmentsIntersect({c, cellCentre(i, j + 1)}, e)) block_n_[idx] = 1;
      }
    }
  }

  // Finite-volume coefficients: diffusion a = D/h^2 through each open face,
  // first-order upwind advection (u/h) from the upstream cell. Outside the
  // grid the air is clean (c = 0): an open edge absorbs.
  const double a = d_m2_s_ / (h_ * h_);
  const double px = std::max(u_m_s_.x, 0.0) / h_, mx = std::max(-u_m_s_.x, 0.0) / h_;
  const double py = std::max(u_m_s_.y, 0.0) / h_, my = std::max(-u_m_s_.y, 0.0) / h_;
  in_e_.assign(total, 0.0);
  in_w_.assign(total, 0.0);
  in_n_.assign(total, 0.0);
  in_s_.assign(total, 0.0);
  out_.assign(total, 0.0);
  for (int j = 0; j < ny_; ++j) {
    for (int i = 0; i < nx_; ++i) {
      const std::size_t p = index(i, j);
      if (solid_[p]) continue;
      const std::size_t e = p + 1, w = p - 1, n = p + stride_, s = p - stride_;
      const double open_e = !block_e_[p] && !solid_[e];
      const double open_w = !block_e_[w] && !solid_[w];
      const double open_n = !block_n_[p] && !solid_[n];
      const double open_s = !block_n_[s] && !solid_[s];
      in_e_[p] = open_e * (a + mx);
      in_w_[p] = open_w * (a + px);
      in_n_[p] = open_n * (a + my);
      in_s_[p] = open_s * (a + py);
      out_[p] = open_e * (a + px) + open_w * (a + mx) + open_n * (a + py) + open_s * (a + my) + k_per_s_;
    }
  }
  scratch_.assign(total, 0.0);
}

bool GasModel::blocked(Vec2 a, Vec2 b) const {
  const Segment s{a, b};
  for (const auto& e : edges_)
    if (boxesOverlap(s, e) && geometry::segmentsIntersect(s, e)) return true;
  return false;
}

GasModel::Stencil GasModel::stencil(Vec2 p) const {
  Stencil st;
  if (nx_ == 0) return st;
  const double fx = (p.x - x0_) / h_ - 0.5, fy = (p.y - y0_) / h_ - 0.5;
  if (!(fx >= -1.0 && fx < nx_ && fy >= -1.0 && fy < ny_)) return st;  // off the grid (or NaN)
  const int i0 = std::min(static_cast<int>(std::floor(fx)), nx_ - 1);
  const int j0 = std::min(static_cast<int>(std::floor(fy)), ny_ - 1);
  const double tx = fx - i0, ty = fy - j0;
  const std::array<std::size_t, 4> cell{index(i0, j0), index(i0 + 1, j0), index(i0, j0 + 1), index(i0 + 1, j0 + 1)};
  const std::array<Vec2, 4> centre{cellCentre(i0, j0), cellCentre(i0 + 1, j0), cellCentre(i0, j0 + 1),
                                   cellCentre(i0 + 1, j0 + 1)};
  const std::array<double, 4> w{(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty};
  bool check = false;
  for (std::size_t c : cell) check = check || near_edge_[c];
  double sum = 0.0;
  for (std::size_t k = 0; k < 4; ++k) {
    if (solid_[cell[k]]) continue;
    if (check && blocked(p, centre[k])) continue;
    st.cell[static_cast<std::size_t>(st.n)] = cell[k];
    st.weight[static_cast<std::size_t>(st.n)] = w[k];
    sum += w[k];
    ++st.n;
  }
  for (std::size_t k = 0; k < static_cast<std::size_t>(st.n); ++k)
    st.weight[k] = sum > 1e-9 ? st.weight[k] / sum : 1.0 / st.n;
  return st;
}

int GasModel::field(std::string_view gas) const {
  for (std::size_t i = 0; i < gases_.size(); ++i)
    if (gases_[i] == gas) return static_cast<int>(i);
  return -1;
}

bool GasModel::inSolidCell(Vec2 p) const {
  const double cx = std::floor((p.x - x0_) / h_), cy = std::floor((p.y - y0_) / h_);
  return cx >= 0 && cx < nx_ && cy >= 0 && cy < ny_ && solid_[index(static_cast<int>(cx), static_cast<int>(cy))];
}

double GasModel::concentration(int f, Vec2 p) const {
  if (f < 0 || static_cast<std::size_t>(f) >= fields_.size() || inSolidCell(p)) return 0.0;
  const Stencil st = stencil(p);
  const auto& c = fields_[static_cast<std::size_t>(f)].c;
  double v = 0.0;
  for (std::size_t k = 0; k < static_cast<std::size_t>(st.n); ++k) v += st.weight[k] * c[st.cell[k]];
  return v;
}

void GasModel::concentrations(Vec2 p, std::span<double> out) const {
  std::fill(out.begin(), out.end(), 0.0);
  if (out.empty() || nx_ == 0 || inSolidCell(p)) return;
  const Stencil st = stencil(p);  // one stencil for every field
  for (std::size_t f = 0; f < std::min(out.size(), fields_.size()); ++f) {
    const auto& c = fields_[f].c;
    double v = 0.0;
    for (std::size_t k = 0; k < static_cast<std::size_t>(st.n); ++k) v += st.weight[k] * c[st.cell[k]];
    out[f] = v;
  }
}

double GasModel::mass(int f) const {
  if (f < 0 || static_cast<std::size_t>(f) >= fields_.size()) return 0.0;
  double sum = 0.0;
  for (double v : fields_[static_cast<std::size_t>(f)].c) sum += v;
  return sum * h_ * h_;
}

std::int64_t GasModel::substeps(double dt_s) const {
  if (!(dt_s > 0.0) || nx_ == 0) return 0;
  // In double first: a long jump (advanceTo over 1e8 s of a steady field) needs
  // more sub-steps than an int holds, and the cast of an out-of-range double is undefined.
  const double n = std::ceil(dt_s / (kStabilityFactor * max_step_s_) - 1e-9);
  constexpr double kMax = 0x1p62;  // exactly representable; far beyond any run's sim time
  if (!(n < kMax)) return static_cast<std::int64_t>(kMax);
  return std::max<std::int64_t>(1, static_cast<std::int64_t>(n));
}

void GasModel::step(std::vector<double>& c, const std::vector<Emitter>& emitters, double t_s, double dt_s, bool emit) {
  const double* __restrict cp = c.data();
  double* __restrict np = scratch_.data();
  const double* __restrict ie = in_e_.data();
  const double* __restrict iw = in_w_.data();
  const double* __restrict in = in_n_.data();
  const double* __restrict is = in_s_.data();
  const double* __restrict out = out_.data();
  const std::size_t s = stride_;
  const std::size_t end = stride_ * (static_cast<std::size_t>(ny_) + 1);
  // Linear over the rows incl. the ring's columns: their coefficients are 0, so they stay 0.
  for (std::size_t p = stride_; p < end; ++p)
    np[p] = cp[p] + dt_s * (ie[p] * cp[p + 1] + iw[p] * cp[p - 1] + in[p] * cp[p + s] + is[p] * cp[p - s] -
                            out[p] * cp[p]);
  if (emit) {
    const double per_area = dt_s / (h_ * h_);
    for (const auto& e : emitters) {
      if (!e.source.activeAt(t_s + kTimeSlack_s)) continue;
      for (const auto& [cell, w] : e.cells) np[cell] += per_area * e.source.rate * w;
    }
  }
  c.swap(scratch_);
}

bool GasModel::steady(int f) const {
  return f >= 0 && static_cast<std::size_t>(f) < fields_.size() && fields_[static_cast<std::size_t>(f)].steady;
}

void GasModel::advanceTo(double t_s) {
  const double dt_s = t_s - t_s_;
  if (!(dt_s > 0.0)) return;
  const std::int64_t n = substeps(dt_s);
  const double dts = n > 0 ? dt_s / static_cast<double>(n) : 0.0;
  for (auto& f : fields_) {
    if (f.steady) {
      // A leak starting or stopping within this interval (generously) ends the steady state.
      for (const auto& e : f.emitters) {
        const auto within = [&](double t) { return t > t_s_ - 1e-6 && t <= t_s + 1e-6; };
        if (within(e.source.start_s) || within(e.source.end_s)) f.steady = false;
      }
      if (f.steady) continue;
    }
    for (std::int64_t k = 0; k < n; ++k) step(f.c, f.emitters, t_s_ + static_cast<double>(k) * dts, dts, true);
  }
  t_s_ = t_s;
}

void GasModel::integrate(std::vector<double>& c, const Emitter& e, double duration_s, bool emit) {
  const std::int64_t n = substeps(duration_s);
  if (n == 0) return;
  Emitter always = e;  // on for the whole interval
  always.source.start_s = -std::numeric_limits<double>::infinity();
  always.source.end_s = std::numeric_limits<double>::infinity();
  const std::vector<Emitter> one{always};
  const double dts = duration_s / static_cast<double>(n);
  for (std::int64_t k = 0; k < n; ++k) step(c, one, 0.0, dts, emit);
}

bool GasModel::solveSteady(std::vector<double>& c, const Emitter& e) const {
  std::vector<double> src(c.size(), 0.0);
  for (const auto& [cell, w] : e.cells) src[cell] += e.source.rate * w / (h_ * h_);
  // Over-relaxation factor from the spectral radius of the Jacobi iteration of
  // the upwind operator on a rectangle the size of the grid (separable:
  // 2 sqrt(a_in a_out) cos(pi h / L) per axis over the diagonal); exact for a
  // room that fills the grid, an estimate otherwise.
  const double a = d_m2_s_ / (h_ * h_);
  const double px = std::max(u_m_s_.x, 0.0) / h_, mx = std::max(-u_m_s_.x, 0.0) / h_;
  const double py = std::max(u_m_s_.y, 0.0) / h_, my = std::max(-u_m_s_.y, 0.0) / h_;
  const double diag = 4.0 * a + px + mx + py + my + k_per_s_;
  const double rho = std::clamp((2.0 * std::sqrt((a + px) * (a + mx)) * std::cos(std::numbers::pi / nx_) +
                                 2.0 * std::sqrt((a + py) * (a + my)) * std::cos(std::numbers::pi / ny_)) /
                                    diag,
                                0.0, 0.999999);
  const double omega = std::clamp(2.0 / (1.0 + std::sqrt(1.0 - rho * rho)), 1.0, 1.95);
  std::vector<double> inv_out(out_.size(), 0.0);
  for (std::size_t p = 0; p < out_.size(); ++p) inv_out[p] = out_[p] > 0.0 ? 1.0 / out_[p] : 0.0;
  const std::size_t s = stride_;
  // Red-black order: cells of one colour depend only on the other's, so a
  // half-sweep has no chain of dependent updates (and converges like lexicographic order).
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    double max_delta = 0.0, max_c = 0.0;
    for (int colour = 0; colour < 2; ++colour) {
      for (int j = 0; j < ny_; ++j) {
        for (std::size_t p = index((j + colour) % 2, j), row_end = index(nx_, j); p < row_end; p += 2) {
          if (inv_out[p] == 0.0) continue;  // solid
          const double target =
              (in_e_[p] * c[p + 1] + in_w_[p] * c[p - 1] + in_n_[p] * c[p + s] + in_s_[p] * c[p - s] + src[p]) *
              inv_out[p];
          const double next = std::max(0.0, c[p] + omega * (target - c[p]));
          max_delta = std::max(max_delta, std::abs(next - c[p]));
          max_c = std::max(max_c, next);
          c[p] = next;
        }
      }
    }
    if (!std::isfinite(max_c)) return false;
    if (sweep > 0 && max_delta <= kSteadyTolerance * max_c) return true;
  }
  return false;
}

bool GasModel::preIntegrate(Field& f, const Emitter& e) {
  const GasSource& s = e.source;
  if (s.start_s >= 0.0) return true;  // nothing yet
  // Every mode of the operator decays at least at rate k: after ln(1/tol)/k the start no longer shows.
  const double settle_s =
      k_per_s_ > 0.0 ? std::log(1.0 / kSettleTolerance) / k_per_s_ : std::numeric_limits<double>::infinity();
  const double on_s = std::min(s.end_s, 0.0) - s.start_s;
  std::vector<double> c(out_.size(), 0.0);
  bool steady = false;
  if (on_s >= settle_s) {
    steady = solveSteady(c, e);
    if (!steady) {
      std::fill(c.begin(), c.end(), 0.0);
      integrate(c, e, settle_s, true);
    }
  } else {
    integrate(c, e, on_s, true);
  }
  if (s.end_s < 0.0) {
    if (-s.end_s >= settle_s) return true;  // long gone: nothing, for good
    integrate(c, e, -s.end_s, false);
    steady = false;
  }
  for (std::size_t i = 0; i < c.size(); ++i) f.c[i] += c[i];
  return steady;
}

}  // namespace inspect::sim
