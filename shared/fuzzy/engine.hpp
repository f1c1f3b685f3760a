#pragma once
// Runs a Fis with MATLAB evalfis semantics. All memory is taken when the
// engine is built; evaluate() is noexcept and allocation-free, so it can sit
// inside the control loop.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "shared/fuzzy/fis.hpp"

namespace inspect::fuzzy {

/// How an Engine evaluates (fixed when it is built).
struct EngineOptions {
  /// Points at which a Mamdani output set is sampled, evenly over the output
  /// range, ends included (MATLAB's NumSamplePoints, default 101).
  std::size_t num_samples = 101;
  /// Clip inputs to their ranges before evaluating. MATLAB's evalfis and
  /// fuzzylite evaluate out-of-range inputs as they are, so this is off.
  bool clip_inputs = false;
};

/// What one evaluate() call did.
enum class EvalStatus {
  kOk,              ///< every output came from fired rules
  kNoRuleFired,     ///< at least one output had no firing rule: it is the middle of its range
  kNonFiniteInput,  ///< an input was NaN/inf: every output is NaN (the caller holds its last command)
  kBadSize,         ///< the spans do not match the system: outputs (those present) are NaN
};

/// A compiled fuzzy inference system with its own workspace. Not thread-safe
/// (one engine per thread); copyable.
class Engine {
 public:
  /// Builds the engine; throws FisError when the Fis is incomplete
  /// (checkComplete) or the options are unusable.
  explicit Engine(Fis fis, EngineOptions options = {});

  /// Evaluates the system: inputs.size() == numInputs(), outputs.size() ==
  /// numOutputs(). Never throws, never allocates.
  EvalStatus evaluate(std::span<const double> inputs, std::span<double> outputs) noexcept;

  std::size_t numInputs() const { return fis_.inputs.size(); }
  std::size_t numOutputs() const { return fis_.outputs.size(); }
  const Fis& fis() const { return fis_; }
  const EngineOptions& options() const { return options_; }
  /// The value an output takes when no rule fires for it (middle of its
  /// range, as MATLAB); output < numOutputs().
  double noRuleValue(std::size_t output) const { return mid_[output]; }
  /// Firing strength of each rule (weight applied) in the last evaluate().
  std::span<const double> firingStrengths() const { return strengths_; }

 private:
  struct MfRef {
    MfType type;
    std::uint32_t param_begin;
    std::uint32_t param_count;
  };
  struct Literal {  // one antecedent entry: input `input` is (not) MF `mf` (flat index)
    std::uint32_t input;
    std::uint32_t mf;
    bool negated;
  };
  struct RuleData {
    std::uint32_t lit_begin;
    std::uint32_t lit_end;
    double weight;
    bool is_or;
  };
  struct Consequent {  // rule `rule` sets output term `term` (MF index within the output), maybe negated
    std::uint32_t rule;
    std::uint32_t term;
    bool negated;
  };

  void evaluateMamdani(std::size_t o, double& out) noexcept;
  void evaluateSugeno(std::size_t o, double& out) noexcept;
  double defuzzify(std::size_t o) const noexcept;

  Fis fis_;
  EngineOptions options_;
  std::vector<double> mid_;                // per output: middle of the range (no-rule value)
  std::vector<double> params_;             // all MF parameters, flat
  std::vector<MfRef> input_mfs_;           // all input MFs, flat
  std::vector<Literal> literals_;
  std::vector<RuleData> rules_;
  std::vector<std::uint32_t> cons_begin_;  // per output, into consequents_ (size outputs + 1)
  std::vector<Consequent> consequents_;
  std::vector<MfRef> output_mfs_;          // all output MFs, flat
  std::vector<std::uint32_t> out_mf_begin_;  // per output, into output_mfs_ (size outputs + 1)
  std::vector<double> out_table_;          // Mamdani: output MF sampled, [flat mf][sample]
  std::vector<std::uint32_t> out_support_;  // Mamdani: [2 * flat mf] first / one-past-last sample with mu > 0
  std::vector<double> out_x_;              // Mamdani: sample positions, [output][sample]

  // Workspace (sized at construction, reused by every evaluate()).
  std::vector<double> x_;          // inputs as evaluated (clipped if asked)
  std::vector<double> degrees_;    // membership degree of every input MF
  std::vector<double> strengths_;  // firing strength of every rule
  std::vector<double> term_w_;     // per output term (x2 for negated): strongest rule, for max aggregation
  std::vector<double> agg_;        // aggregated output set over the samples
};

}  // namespace inspect::fuzzy
