#include "shared/fuzzy/lookup_surface.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "shared/fuzzy/fis_error.hpp"

namespace inspect::fuzzy {

LookupSurface::LookupSurface(const Fis& fis, LookupOptions options, EngineOptions engine_options)
    : fis_(fis), engine_options_(engine_options) {
  Engine engine(fis_, engine_options_);
  dims_ = engine.numInputs();
  n_out_ = engine.numOutputs();
  if (dims_ < 1 || dims_ > kMaxInputs) {
    throw FisError("fis '" + fis_.name + "': a lookup surface takes 1 to 3 inputs, the system has " +
                   std::to_string(dims_));
  }
  points_ = options.points_per_input;
  if (points_ == 0) points_ = dims_ == 1 ? kDefaultPoints1d : dims_ == 2 ? kDefaultPoints2d : kDefaultPoints3d;
  if (points_ < 2 || points_ > 100000) {
    throw FisError("fis '" + fis_.name + "': points_per_input must lie in [2, 100000], got " + std::to_string(points_));
  }
  std::size_t nodes = 1;
  for (std::size_t d = 0; d < dims_; ++d) {
    min_[d] = fis_.inputs[d].min;
    max_[d] = fis_.inputs[d].max;
    step_[d] = (max_[d] - min_[d]) / static_cast<double>(points_ - 1);
    stride_[d] = nodes;
    nodes *= points_;
  }
  if (nodes > 50'000'000 / std::max<std::size_t>(n_out_, 1)) {
    throw FisError("fis '" + fis_.name + "': lookup surface of " + std::to_string(nodes) + " nodes is too large");
  }
  values_.resize(nodes * n_out_);
  double x[kMaxInputs] = {};
  for (std::size_t node = 0; node < nodes; ++node) {
    for (std::size_t d = 0; d < dims_; ++d) {
      const std::size_t idx = (node / stride_[d]) % points_;
      // The last node sits exactly on max, not on min + (n-1) * step.
      x[d] = idx + 1 == points_ ? max_[d] : min_[d] + step_[d] * static_cast<double>(idx);
    }
    engine.evaluate(std::span<const double>(x, dims_), std::span<double>(values_.data() + node * n_out_, n_out_));
  }
}

EvalStatus LookupSurface::evaluate(std::span<const double> inputs, std::span<double> outputs) const noexcept {
  if (inputs.size() != dims_ || outputs.size() != n_out_) {
    std::fill(outputs.begin(), outputs.end(), std::numeric_limits<double>::quiet_NaN());
    return EvalStatus::kBadSize;
  }
  std::size_t base = 0;
  double frac[kMaxInputs] = {};
  for (std::size_t d = 0; d < dims_; ++d) {
    if (!std::isfinite(inputs[d])) {
      std::fill(outputs.begin(), outputs.end(), std::numeric_limits<double>::quiet_NaN());
      return EvalStatus::kNonFiniteInput;
    }
    const double u = (std::clamp(inputs[d], min_[d], max_[d]) - min_[d]) / step_[d];
    std::size_t cell = static_cast<std::size_t>(u);
    if (cell >= points_ - 1) cell = points_ - 2;  // x == max: last cell, fraction 1
    frac[d] = u - static_cast<double>(cell);
    base += cell * stride_[d];
  }
  std::fill(outputs.begin(), outputs.end(), 0.0);
  const std::size_t corners = std::size_t{1} << dims_;
  for (std::size_t c = 0; c < corners; ++c) {
    double w = 1.0;
    std::size_t node = base;
    for (std::size_t d = 0; d < dims_; ++d) {
      if (c & (std::size_t{1} << d)) {
        w *= frac[d];
        node += stride_[d];
      } else {
        w *= 1.0 - frac[d];
      }
    }
    const double* v = values_.data() + node * n_out_;
    for (std::size_t o = 0; o < n_out_; ++o) outputs[o] += w * v[o];
  }
  return EvalStatus::kOk;
}

std::vector<double> LookupSurface::maxInterpolationErrorPerOutput(std::size_t refine) const {
  if (refine == 0) refine = dims_ <= 2 ? 4 : 2;
  Engine engine(fis_, engine_options_);
  const std::size_t fine = (points_ - 1) * refine + 1;
  std::size_t total = 1;
  for (std::size_t d = 0; d < dims_; ++d) total *= fine;
  std::vector<double> err(n_out_, 0.0);
  std::vector<double> direct(n_out_), interp(n_out_);
  double x[kMaxInputs] = {};
  for (std::size_t node = 0; node < total; ++node) {
    std::size_t rest = node;
    for (std::size_t d = 0; d < dims_; ++d) {
      const std::size_t idx = rest % fine;
      rest /= fine;
      x[d] = idx + 1 == fine ? max_[d] : min_[d] + (max_[d] - min_[d]) * static_cast<double>(idx) / static_cast<double>(fine - 1);
    }
    engine.evaluate(std::span<const double>(x, dims_), direct);
    evaluate(std::span<const double>(x, dims_), interp);
    for (std::size_t o = 0; o < n_out_; ++o) err[o] = std::max(err[o], std::abs(direct[o] - interp[o]));
  }
  return err;
}

double LookupSurface::maxInterpolationError(std::size_t refine) const {
  const auto per = maxInterpolationErrorPerOutput(refine);
  return per.empty() ? 0.0 : *std::max_element(per.begin(), per.end());
}

}  // namespace inspect::fuzzy
