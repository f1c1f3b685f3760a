#include "shared/fuzzy/fis.hpp"

#include <array>
#include <cmath>
#include <utility>

#include "shared/fuzzy/fis_error.hpp"

namespace inspect::fuzzy {

namespace {

template <typename E>
struct Spelling {
  E value;
  std::string_view name;
};

constexpr std::array<Spelling<FisType>, 2> kFisTypes{{{FisType::kMamdani, "mamdani"}, {FisType::kSugeno, "sugeno"}}};
constexpr std::array<Spelling<AndMethod>, 2> kAnd{{{AndMethod::kMin, "min"}, {AndMethod::kProd, "prod"}}};
constexpr std::array<Spelling<OrMethod>, 2> kOr{{{OrMethod::kMax, "max"}, {OrMethod::kProbor, "probor"}}};
constexpr std::array<Spelling<ImpMethod>, 2> kImp{{{ImpMethod::kMin, "min"}, {ImpMethod::kProd, "prod"}}};
constexpr std::array<Spelling<AggMethod>, 3> kAgg{
    {{AggMethod::kMax, "max"}, {AggMethod::kSum, "sum"}, {AggMethod::kProbor, "probor"}}};
constexpr std::array<Spelling<DefuzzMethod>, 7> kDefuzz{{{DefuzzMethod::kCentroid, "centroid"},
                                                         {DefuzzMethod::kBisector, "bisector"},
                                                         {DefuzzMethod::kMom, "mom"},
                                                         {DefuzzMethod::kSom, "som"},
                                                         {DefuzzMethod::kLom, "lom"},
                                                         {DefuzzMethod::kWtaver, "wtaver"},
                                                         {DefuzzMethod::kWtsum, "wtsum"}}};

template <typename E, std::size_t N>
std::string_view nameOf(const std::array<Spelling<E>, N>& table, E v) {
  for (const auto& s : table) {
    if (s.value == v) return s.name;
  }
  return "?";
}

template <typename E, std::size_t N>
std::optional<E> valueOf(const std::array<Spelling<E>, N>& table, std::string_view name) {
  for (const auto& s : table) {
    if (s.name == name) return s.value;
  }
  return std::nullopt;
}

using Where = FisProblem::Where;

void checkVariable(const Fis& fis, const Variable& v, Where where, std::size_t index,
                   std::vector<FisProblem>& out) {
  const bool is_output = where == Where::kOutput;
  auto add = [&](std::optional<std::size_t> mf, std::string key, std::string msg) {
    out.push_back(FisProblem{where, index, mf, std::move(key), std::move(msg)});
  };
  if (v.name.empty()) add(std::nullopt, "Name", "the name is empty");
  if (!std::isfinite(v.min) || !std::isfinite(v.max) || !(v.min < v.max)) {
    add(std::nullopt, "Range", "Range needs two finite numbers with min < max");
  }
  if (v.mfs.empty()) add(std::nullopt, "NumMFs", "the variable has no membership functions");
  for (std::size_t j = 0; j < v.mfs.size(); ++j) {
    const MembershipFunction& mf = v.mfs[j];
    const std::string tag = "MF" + std::to_string(j + 1);
    if (mf.name.empty()) add(j, "", tag + ": the name is empty");
    for (std::size_t k = 0; k < j; ++k) {
      if (!mf.name.empty() && v.mfs[k].name == mf.name) {
        add(j, "", tag + ": name '" + mf.name + "' is already used by MF" + std::to_string(k + 1));
        break;
      }
    }
    const bool sugeno_out = is_output && fis.type == FisType::kSugeno;
    if (sugeno_out && !isSugenoOutputType(mf.type)) {
      add(j, "", tag + ": a Sugeno output needs 'constant' or 'linear', got '" + std::string(mfTypeName(mf.type)) + "'");
      continue;
    }
    if (!sugeno_out && isSugenoOutputType(mf.type)) {
      add(j, "",
          tag + ": '" + std::string(mfTypeName(mf.type)) + "' is only allowed for outputs of a Sugeno system");
      continue;
    }
    std::string p = mfParamProblem(mf.type, mf.params, fis.inputs.size());
    if (!p.empty()) add(j, "", tag + ": " + p);
  }
}

}  // namespace

std::string_view toString(FisType v) { return nameOf(kFisTypes, v); }
std::string_view toString(AndMethod v) { return nameOf(kAnd, v); }
std::string_view toString(OrMethod v) { return nameOf(kOr, v); }
std::string_view toString(ImpMethod v) { return nameOf(kImp, v); }
std::string_view toString(AggMethod v) { return nameOf(kAgg, v); }
std::string_view toString(DefuzzMethod v) { return nameOf(kDefuzz, v); }
std::optional<FisType> parseFisType(std::string_view s) { return valueOf(kFisTypes, s); }
std::optional<AndMethod> parseAndMethod(std::string_view s) { return valueOf(kAnd, s); }
std::optional<OrMethod> parseOrMethod(std::string_view s) { return valueOf(kOr, s); }
std::optional<ImpMethod> parseImpMethod(std::string_view s) { return valueOf(kImp, s); }
std::optional<AggMethod> parseAggMethod(std::string_view s) { return valueOf(kAgg, s); }
std::optional<DefuzzMethod> parseDefuzzMethod(std::string_view s) { return valueOf(kDefuzz, s); }

bool isSugenoDefuzz(DefuzzMethod m) { return m == DefuzzMethod::kWtaver || m == DefuzzMethod::kWtsum; }

std::vector<FisProblem> fisProblems(const Fis& fis) {
  std::vector<FisProblem> out;
  auto sys = [&](std::string key, std::string msg) {
    out.push_back(FisProblem{Where::kSystem, 0, std::nullopt, std::move(key), std::move(msg)});
  };
  if (fis.inputs.empty()) sys("NumInputs", "the system has no inputs");
  if (fis.outputs.empty()) sys("NumOutputs", "the system has no outputs");
  if (fis.rules.empty()) sys("NumRules", "the system has no rules");
  if (fis.type == FisType::kSugeno && !isSugenoDefuzz(fis.defuzz_method)) {
    sys("DefuzzMethod", "a Sugeno system needs DefuzzMethod 'wtaver' or 'wtsum', got '" +
                            std::string(toString(fis.defuzz_method)) + "'");
  }
  if (fis.type == FisType::kMamdani && isSugenoDefuzz(fis.defuzz_method)) {
    sys("DefuzzMethod", "'" + std::string(toString(fis.defuzz_method)) +
                            "' is a Sugeno defuzzifier; a Mamdani system needs centroid, bisector, mom, som or lom");
  }

  for (std::size_t i = 0; i < fis.inputs.size(); ++i) checkVariable(fis, fis.inputs[i], Where::kInput, i, out);
  for (std::size_t i = 0; i < fis.outputs.size(); ++i) checkVariable(fis, fis.outputs[i], Where::kOutput, i, out);

  // Variable names must be unique across inputs and outputs (rules, tools
  // and fuzzylite address variables by name).
  std::vector<std::pair<Where, std::size_t>> all;
  for (std::size_t i = 0; i < fis.inputs.size(); ++i) all.emplace_back(Where::kInput, i);
  for (std::size_t i = 0; i < fis.outputs.size(); ++i) all.emplace_back(Where::kOutput, i);
  auto var = [&](const std::pair<Where, std::size_t>& w) -> const Variable& {
    return w.first == Where::kInput ? fis.inputs[w.second] : fis.outputs[w.second];
  };
  for (std::size_t a = 0; a < all.size(); ++a) {
    for (std::size_t b = 0; b < a; ++b) {
      if (!var(all[a]).name.empty() && var(all[a]).name == var(all[b]).name) {
        out.push_back(FisProblem{all[a].first, all[a].second, std::nullopt, "Name",
                                 "variable name '" + var(all[a]).name + "' is used twice"});
        break;
      }
    }
  }

  for (std::size_t r = 0; r < fis.rules.size(); ++r) {
    const Rule& rule = fis.rules[r];
    const std::string tag = "rule " + std::to_string(r + 1);
    auto add = [&](std::string msg) { out.push_back(FisProblem{Where::kRule, r, std::nullopt, "", std::move(msg)}); };
    if (rule.antecedent.size() != fis.inputs.size()) {
      add(tag + " has " + std::to_string(rule.antecedent.size()) + " antecedent entries, the system has " +
          std::to_string(fis.inputs.size()) + " inputs");
      continue;
    }
    if (rule.consequent.size() != fis.outputs.size()) {
      add(tag + " has " + std::to_string(rule.consequent.size()) + " consequent entries, the system has " +
          std::to_string(fis.outputs.size()) + " outputs");
      continue;
    }
    bool any_in = false;
    for (std::size_t i = 0; i < rule.antecedent.size(); ++i) {
      const int k = rule.antecedent[i];
      if (k == 0) continue;
      any_in = true;
      const std::size_t n = fis.inputs[i].mfs.size();
      if (static_cast<std::size_t>(k < 0 ? -static_cast<long>(k) : k) > n) {
        add(tag + " refers to MF " + std::to_string(k < 0 ? -k : k) + " of input " + std::to_string(i + 1) +
            ", which has " + std::to_string(n));
      }
    }
    bool any_out = false;
    for (std::size_t o = 0; o < rule.consequent.size(); ++o) {
      const int k = rule.consequent[o];
      if (k == 0) continue;
      any_out = true;
      const std::size_t n = fis.outputs[o].mfs.size();
      if (static_cast<std::size_t>(k < 0 ? -static_cast<long>(k) : k) > n) {
        add(tag + " refers to MF " + std::to_string(k < 0 ? -k : k) + " of output " + std::to_string(o + 1) +
            ", which has " + std::to_string(n));
      }
      if (k < 0 && fis.type == FisType::kSugeno) {
        add(tag + ": a negated (NOT) consequent has no meaning in a Sugeno system (output " + std::to_string(o + 1) +
            ")");
      }
    }
    if (!any_in) add(tag + " has no antecedent (every input is 0 = don't care)");
    if (!any_out) add(tag + " has no consequent (every output is 0)");
    if (!std::isfinite(rule.weight) || rule.weight < 0.0 || rule.weight > 1.0) {
      add(tag + ": weight must lie in [0, 1]");
    }
    if (rule.connection != Connection::kAnd && rule.connection != Connection::kOr) {
      add(tag + ": connection must be 1 (AND) or 2 (OR)");
    }
  }
  return out;
}

std::string describeLocation(const Fis& fis, const FisProblem& p) {
  switch (p.where) {
    case Where::kSystem: return "system";
    case Where::kInput:
      return "input " + std::to_string(p.index + 1) +
             (p.index < fis.inputs.size() ? " '" + fis.inputs[p.index].name + "'" : std::string());
    case Where::kOutput:
      return "output " + std::to_string(p.index + 1) +
             (p.index < fis.outputs.size() ? " '" + fis.outputs[p.index].name + "'" : std::string());
    case Where::kRule: return "rule " + std::to_string(p.index + 1);
  }
  return "?";
}

void checkComplete(const Fis& fis) {
  const auto problems = fisProblems(fis);
  if (problems.empty()) return;
  const FisProblem& p = problems.front();
  std::string where = p.where == Where::kRule ? std::string() : describeLocation(fis, p) + ": ";
  std::string more = problems.size() > 1 ? " (and " + std::to_string(problems.size() - 1) + " more)" : "";
  throw FisError("fis '" + fis.name + "': " + where + p.message + more);
}

}  // namespace inspect::fuzzy
