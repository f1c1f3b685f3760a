#pragma once
// A fuzzy controller with 1 to 3 inputs compiled into a regular grid over
// its input ranges and read back by multilinear interpolation: a fast,
// branch-light replacement for Engine inside a high-rate loop.
#include <cstddef>
#include <span>
#include <vector>

#include "shared/fuzzy/engine.hpp"
#include "shared/fuzzy/fis.hpp"

namespace inspect::fuzzy {

/// How finely a LookupSurface samples its inputs.
struct LookupOptions {
  /// Grid points per input, ends included; 0 picks the default for the
  /// number of inputs (kDefaultPoints1d / 2d / 3d).
  std::size_t points_per_input = 0;
};

/// Precomputed outputs of a Fis on a grid over its inputs' ranges.
class LookupSurface {
 public:
  static constexpr std::size_t kDefaultPoints1d = 1001;
  static constexpr std::size_t kDefaultPoints2d = 201;
  static constexpr std::size_t kDefaultPoints3d = 41;
  static constexpr std::size_t kMaxInputs = 3;

  /// Compiles the surface by evaluating the Fis at every grid point. Throws
  /// FisError for an incomplete Fis or more than kMaxInputs inputs.
  explicit LookupSurface(const Fis& fis, LookupOptions options = {}, EngineOptions engine_options = {});

  /// Interpolated outputs. Inputs outside their range are clamped to it (a
  /// grid cannot extrapolate); non-finite inputs give NaN outputs and
  /// kNonFiniteInput. Never throws, never allocates.
  EvalStatus evaluate(std::span<const double> inputs, std::span<double> outputs) const noexcept;

  /// Largest |surface - direct evaluation| over all outputs on a grid
  /// `refine` times finer than the surface's (so it includes the cell centres
  /// where interpolation is worst); refine 0 picks 4 for 1-2 inputs, 2 for 3.
  double maxInterpolationError(std::size_t refine = 0) const;
  /// The same, one figure per output.
  std::vector<double> maxInterpolationErrorPerOutput(std::size_t refine = 0) const;

  std::size_t numInputs() const { return dims_; }
  std::size_t numOutputs() const { return n_out_; }
  std::size_t pointsPerInput() const { return points_; }

 private:
  Fis fis_;
  EngineOptions engine_options_;
  std::size_t dims_ = 0;
  std::size_t n_out_ = 0;
  std::size_t points_ = 0;
  double min_[kMaxInputs] = {};
  double max_[kMaxInputs] = {};
  double step_[kMaxInputs] = {};
  std::size_t stride_[kMaxInputs] = {};  // grid-node stride per input
  std::vector<double> values_;           // [node][output]
};

}  // namespace inspect::fuzzy
