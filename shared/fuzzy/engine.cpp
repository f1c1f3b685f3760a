#include "shared/fuzzy/engine.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "shared/fuzzy/fis_error.hpp"

namespace inspect::fuzzy {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::uint32_t u32(std::size_t v) { return static_cast<std::uint32_t>(v); }

// Implies one output term (sampled MF `mu`, strength w) and aggregates it into
// `a`; one instance per method combination keeps the sample loop branch-free.
template <AggMethod kAgg, bool kImpMin, bool kNegated>
void accumulateInto(const double* mu, double* a, std::size_t n, double w) noexcept {
  for (std::size_t k = 0; k < n; ++k) {
    const double m = kNegated ? 1.0 - mu[k] : mu[k];
    const double v = kImpMin ? (w < m ? w : m) : w * m;
    if constexpr (kAgg == AggMethod::kMax) {
      a[k] = a[k] > v ? a[k] : v;
    } else if constexpr (kAgg == AggMethod::kSum) {
      a[k] += v;
    } else {
      a[k] = a[k] + v - a[k] * v;
    }
  }
}

}  // namespace

Engine::Engine(Fis fis, EngineOptions options) : fis_(std::move(fis)), options_(options) {
  checkComplete(fis_);
  if (options_.num_samples < 3 || options_.num_samples > 1000000) {
    throw FisError("fis '" + fis_.name + "': num_samples must lie in [3, 1000000], got " +
                   std::to_string(options_.num_samples));
  }
  const std::size_t n_in = fis_.inputs.size();
  const std::size_t n_out = fis_.outputs.size();

  std::vector<std::uint32_t> in_begin;
  for (const auto& v : fis_.inputs) {
    in_begin.push_back(u32(input_mfs_.size()));
    for (const auto& mf : v.mfs) {
      input_mfs_.push_back(MfRef{mf.type, u32(params_.size()), u32(mf.params.size())});
      params_.insert(params_.end(), mf.params.begin(), mf.params.end());
    }
  }
  for (const auto& v : fis_.outputs) {
    out_mf_begin_.push_back(u32(output_mfs_.size()));
    mid_.push_back(0.5 * (v.min + v.max));
    for (const auto& mf : v.mfs) {
      output_mfs_.push_back(MfRef{mf.type, u32(params_.size()), u32(mf.params.size())});
      params_.insert(params_.end(), mf.params.begin(), mf.params.end());
    }
  }
  out_mf_begin_.push_back(u32(output_mfs_.size()));

  for (const auto& r : fis_.rules) {
    RuleData d{u32(literals_.size()), 0, r.weight, r.connection == Connection::kOr};
    for (std::size_t i = 0; i < n_in; ++i) {
      const int k = r.antecedent[i];
      if (k == 0) continue;  // don't care: MATLAB skips it (1 for AND, 0 for OR)
      literals_.push_back(Literal{u32(i), in_begin[i] + u32(std::abs(k) - 1), k < 0});
    }
    d.lit_end = u32(literals_.size());
    rules_.push_back(d);
  }
  for (std::size_t o = 0; o < n_out; ++o) {
    cons_begin_.push_back(u32(consequents_.size()));
    for (std::size_t r = 0; r < fis_.rules.size(); ++r) {
      const int k = fis_.rules[r].consequent[o];
      if (k == 0) continue;
      consequents_.push_back(Consequent{u32(r), u32(std::abs(k) - 1), k < 0});
    }
  }
  cons_begin_.push_back(u32(consequents_.size()));

  std::size_t max_terms = 0;
  for (const auto& v : fis_.outputs) max_terms = std::max(max_terms, v.mfs.size());
  if (fis_.type == FisType::kMamdani) {
    // Output MFs never change: sample them once on MATLAB's grid x_k = min + k * step.
    const std::size_t n = options_.num_samples;
    out_table_.resize(output_mfs_.size() * n);
    out_support_.resize(output_mfs_.size() * 2);
    out_x_.resize(n_out * n);
    for (std::size_t o = 0; o < n_out; ++o) {
      const Variable& v = fis_.outputs[o];
      const double step = (v.max - v.min) / static_cast<double>(n - 1);
      for (std::size_t k = 0; k < n; ++k) out_x_[o * n + k] = v.min + step * static_cast<double>(k);
      for (std::size_t j = 0; j < v.mfs.size(); ++j) {
        const std::size_t flat = out_mf_begin_[o] + j;
        std::size_t first = n, last = 0;
        for (std::size_t k = 0; k < n; ++k) {
          const double mu = mfValue(v.mfs[j].type, v.mfs[j].params, out_x_[o * n + k]);
          out_table_[flat * n + k] = mu;
          if (mu > 0.0) {
            first = std::min(first, k);
            last = k + 1;
          }
        }
        // Outside its support a term adds exactly nothing (max(a, 0) = a + 0 = a),
        // so the sample loops may skip it.
        out_support_[2 * flat] = u32(first < last ? first : 0);
        out_support_[2 * flat + 1] = u32(first < last ? last : 0);
      }
    }
    agg_.resize(n);
  }
  x_.resize(n_in);
  degrees_.resize(input_mfs_.size());
  strengths_.resize(rules_.size());
  term_w_.resize(2 * max_terms);
}

EvalStatus Engine::evaluate(std::span<const double> inputs, std::span<double> outputs) noexcept {
  if (inputs.size() != numInputs() || outputs.size() != numOutputs()) {
    std::fill(outputs.begin(), outputs.end(), kNaN);
    return EvalStatus::kBadSize;
  }
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    if (!std::isfinite(inputs[i])) {
      std::fill(outputs.begin(), outputs.end(), kNaN);
      return EvalStatus::kNonFiniteInput;
    }
    const Variable& v = fis_.inputs[i];
    x_[i] = options_.clip_inputs ? std::clamp(inputs[i], v.min, v.max) : inputs[i];
  }

  // Fuzzify.
  std::size_t flat = 0;
  for (std::size_t i = 0; i < x_.size(); ++i) {
    const std::size_t count = fis_.inputs[i].mfs.size();
    for (std::size_t j = 0; j < count; ++j, ++flat) {
      const MfRef& m = input_mfs_[flat];
      degrees_[flat] = mfValue(m.type, std::span<const double>(params_.data() + m.param_begin, m.param_count), x_[i]);
    }
  }

  // Firing strengths: AND/OR over the literals (NOT = 1 - mu), times the weight.
  const bool and_min = fis_.and_method == AndMethod::kMin;
  const bool or_max = fis_.or_method == OrMethod::kMax;
  for (std::size_t r = 0; r < rules_.size(); ++r) {
    const RuleData& d = rules_[r];
    double w = d.is_or ? 0.0 : 1.0;
    for (std::uint32_t l = d.lit_begin; l < d.lit_end; ++l) {
      const Literal& lit = literals_[l];
      const double mu = lit.negated ? 1.0 - degrees_[lit.mf] : degrees_[lit.mf];
      if (d.is_or) {
        w = or_max ? std::max(w, mu) : w + mu - w * mu;
      } else {
        w = and_min ? std::min(w, mu) : w * mu;
      }
    }
    strengths_[r] = w * d.weight;
  }

  EvalStatus status = EvalStatus::kOk;
  for (std::size_t o = 0; o < outputs.size(); ++o) {
    double fired = 0.0;
    for (std::uint32_t c = cons_begin_[o]; c < cons_begin_[o + 1]; ++c) fired += strengths_[consequents_[c].rule];
    if (!(fired > 0.0)) {
      // MATLAB: "no rules fired for output o; defuzzified output set to the mean of its range".
      outputs[o] = noRuleValue(o);
      status = EvalStatus::kNoRuleFired;
      continue;
    }
    if (fis_.type == FisType::kMamdani) {
      evaluateMamdani(o, outputs[o]);
    } else {
      evaluateSugeno(o, outputs[o]);
    }
  }
  return status;
}

void Engine::evaluateMamdani(std::size_t o, double& out) noexcept {
  const std::size_t n = options_.num_samples;
  const bool imp_min = fis_.imp_method == ImpMethod::kMin;
  std::fill(agg_.begin(), agg_.end(), 0.0);

  // Adds one implied term (strength w on output MF `term`, maybe negated) into agg_.
  auto accumulate = [&](std::size_t term, bool negated, double w) {
    const std::size_t flat = out_mf_begin_[o] + term;
    // NOT mu is positive wherever mu < 1, so a negated term spans every sample.
    const std::size_t begin = negated ? 0 : out_support_[2 * flat];
    const std::size_t end = negated ? n : out_support_[2 * flat + 1];
    const double* mu = out_table_.data() + flat * n + begin;
    double* a = agg_.data() + begin;
    const std::size_t count = end - begin;
    const int kind = (static_cast<int>(fis_.agg_method) * 2 + (imp_min ? 1 : 0)) * 2 + (negated ? 1 : 0);
    switch (kind) {
      case 0: accumulateInto<AggMethod::kMax, false, false>(mu, a, count, w); break;
      case 1: accumulateInto<AggMethod::kMax, false, true>(mu, a, count, w); break;
      case 2: accumulateInto<AggMethod::kMax, true, false>(mu, a, count, w); break;
      case 3: accumulateInto<AggMethod::kMax, true, true>(mu, a, count, w); break;
      case 4: accumulateInto<AggMethod::kSum, false, false>(mu, a, count, w); break;
      case 5: accumulateInto<AggMethod::kSum, false, true>(mu, a, count, w); break;
      case 6: accumulateInto<AggMethod::kSum, true, false>(mu, a, count, w); break;
      case 7: accumulateInto<AggMethod::kSum, true, true>(mu, a, count, w); break;
      case 8: accumulateInto<AggMethod::kProbor, false, false>(mu, a, count, w); break;
      case 9: accumulateInto<AggMethod::kProbor, false, true>(mu, a, count, w); break;
      case 10: accumulateInto<AggMethod::kProbor, true, false>(mu, a, count, w); break;
      default: accumulateInto<AggMethod::kProbor, true, true>(mu, a, count, w); break;
    }
  };

  if (fis_.agg_method == AggMethod::kMax) {
    // With max aggregation, rules on the same term reduce to the strongest one
    // exactly (min and prod are monotone in w), so each term is implied once.
    const std::size_t terms = fis_.outputs[o].mfs.size();
    std::fill(term_w_.begin(), term_w_.begin() + static_cast<std::ptrdiff_t>(2 * terms), 0.0);
    for (std::uint32_t c = cons_begin_[o]; c < cons_begin_[o + 1]; ++c) {
      const Consequent& cq = consequents_[c];
      double& slot = term_w_[2 * cq.term + (cq.negated ? 1 : 0)];
      slot = std::max(slot, strengths_[cq.rule]);
    }
    for (std::size_t t = 0; t < 2 * terms; ++t) {
      if (term_w_[t] > 0.0) accumulate(t / 2, (t % 2) == 1, term_w_[t]);
    }
  } else {
    // Rules that do not fire add nothing under sum and probor (x + 0 = x).
    for (std::uint32_t c = cons_begin_[o]; c < cons_begin_[o + 1]; ++c) {
      const Consequent& cq = consequents_[c];
      const double w = strengths_[cq.rule];
      if (w > 0.0) accumulate(cq.term, cq.negated, w);
    }
  }
  out = defuzzify(o);
}

double Engine::defuzzify(std::size_t o) const noexcept {
  const Variable& v = fis_.outputs[o];
  const std::size_t n = options_.num_samples;
  const double step = (v.max - v.min) / static_cast<double>(n - 1);
  const double* a = agg_.data();
  const double* x = out_x_.data() + o * n;
  auto xAt = [&](std::size_t k) { return x[k]; };

  double area = 0.0;
  double moment = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    area += a[k];
    moment += a[k] * x[k];
  }
  // MATLAB: an empty output set (e.g. every implied MF is zero on the samples)
  // defuzzifies to the middle of the range.
  if (!(area > 0.0)) return noRuleValue(o);

  switch (fis_.defuzz_method) {
    case DefuzzMethod::kCentroid: return moment / area;
    case DefuzzMethod::kBisector: {
      // MATLAB: the first sample at which the running area reaches half the total.
      double sub = 0.0;
      std::size_t k = 0;
      for (; k < n; ++k) {
        sub += a[k];
        if (sub >= area / 2.0) break;
      }
      return xAt(std::min(k, n - 1));
    }
    case DefuzzMethod::kMom:
    case DefuzzMethod::kSom:
    case DefuzzMethod::kLom: {
      const double peak = *std::max_element(a, a + n);
      if (fis_.defuzz_method == DefuzzMethod::kMom) {
        // MATLAB: mean of every sample where the set reaches its maximum.
        double sum = 0.0;
        double count = 0.0;
        for (std::size_t k = 0; k < n; ++k) {
          if (a[k] == peak) {
            sum += static_cast<double>(k);
            count += 1.0;
          }
        }
        return v.min + step * (sum / count);
      }
      // MATLAB: smallest / largest of maximum in ABSOLUTE value; the first on ties.
      const bool smallest = fis_.defuzz_method == DefuzzMethod::kSom;
      std::size_t best = n;
      for (std::size_t k = 0; k < n; ++k) {
        if (a[k] != peak) continue;
        if (best == n) {
          best = k;
          continue;
        }
        const double cur = std::abs(xAt(k));
        const double old = std::abs(xAt(best));
        if (smallest ? cur < old : cur > old) best = k;
      }
      return xAt(best);
    }
    case DefuzzMethod::kWtaver:
    case DefuzzMethod::kWtsum: break;
  }
  return noRuleValue(o);
}

void Engine::evaluateSugeno(std::size_t o, double& out) noexcept {
  double sum_wz = 0.0;
  double sum_w = 0.0;
  const std::span<const double> xs(x_);
  for (std::uint32_t c = cons_begin_[o]; c < cons_begin_[o + 1]; ++c) {
    const Consequent& cq = consequents_[c];
    const double w = strengths_[cq.rule];
    const MfRef& m = output_mfs_[out_mf_begin_[o] + cq.term];
    const double z = sugenoOutput(m.type, std::span<const double>(params_.data() + m.param_begin, m.param_count), xs);
    sum_wz += w * z;
    sum_w += w;
  }
  out = fis_.defuzz_method == DefuzzMethod::kWtsum ? sum_wz : sum_wz / sum_w;
}

}  // namespace inspect::fuzzy
