#pragma once
// A fuzzy inference system as plain data, mirroring a MATLAB .fis file. It is
// read by fis_reader, written by fis_writer and run by Engine; it does no
// inference itself.
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "shared/fuzzy/membership_function.hpp"

namespace inspect::fuzzy {

/// Type='mamdani' or Type='sugeno'.
enum class FisType { kMamdani, kSugeno };
/// AndMethod: min or prod.
enum class AndMethod { kMin, kProd };
/// OrMethod: max or probor (a + b - ab).
enum class OrMethod { kMax, kProbor };
/// ImpMethod: min (clip) or prod (scale).
enum class ImpMethod { kMin, kProd };
/// AggMethod: max, sum (unbounded) or probor.
enum class AggMethod { kMax, kSum, kProbor };
/// DefuzzMethod: the first five are Mamdani's, wtaver/wtsum Sugeno's.
enum class DefuzzMethod { kCentroid, kBisector, kMom, kSom, kLom, kWtaver, kWtsum };
/// Rule connection (the number after ':'): 1 AND, 2 OR.
enum class Connection { kAnd = 1, kOr = 2 };

/// An input or output variable: `[Input1]` / `[Output1]`.
struct Variable {
  std::string name;
  double min = 0.0;
  double max = 1.0;
  std::vector<MembershipFunction> mfs;

  bool operator==(const Variable&) const = default;
};

/// One line of [Rules]: `1 -2 0, 3 (0.5) : 1`. Indices are 1-based MF
/// numbers, negative = NOT, 0 = don't care (antecedent) / no effect
/// (consequent).
struct Rule {
  std::vector<int> antecedent;
  std::vector<int> consequent;
  double weight = 1.0;
  Connection connection = Connection::kAnd;

  bool operator==(const Rule&) const = default;
};

/// The whole system, as a .fis file holds it.
struct Fis {
  /// Comment lines ('%' or '#') before [System], without the marker; kept on
  /// round trips so that a file's header (e.g. its citation) survives.
  std::vector<std::string> comments;
  std::string name;
  FisType type = FisType::kMamdani;
  std::string version = "2.0";
  /// MATLAB R2018b+ writes DisableStructuralChecks=0; kept when present.
  std::optional<int> disable_structural_checks;
  AndMethod and_method = AndMethod::kMin;
  OrMethod or_method = OrMethod::kMax;
  ImpMethod imp_method = ImpMethod::kMin;
  AggMethod agg_method = AggMethod::kMax;
  DefuzzMethod defuzz_method = DefuzzMethod::kCentroid;
  std::vector<Variable> inputs;
  std::vector<Variable> outputs;
  std::vector<Rule> rules;

  bool operator==(const Fis&) const = default;
};

/// One reason a Fis is unusable, with where it is, so that the .fis reader
/// can name the line and checkComplete() the variable or rule.
struct FisProblem {
  enum class Where { kSystem, kInput, kOutput, kRule };
  Where where = Where::kSystem;
  std::size_t index = 0;           ///< 0-based variable or rule index
  std::optional<std::size_t> mf;   ///< 0-based MF index for MF problems
  std::string key;                 ///< .fis key concerned ("Range", "DefuzzMethod", ...), may be empty
  std::string message;             ///< e.g. "MF3: trimf needs 3 parameters, got 2"
};

/// The problems that make a Fis unusable (empty when it is complete): no
/// inputs/outputs/rules, bad ranges, bad MF parameters, MF types that do not
/// fit the system type, rules that refer to missing MFs, duplicate names.
std::vector<FisProblem> fisProblems(const Fis& fis);
/// "input 2 'ec'", "output 1 'kpx'", "rule 7" or "system": where a problem is.
std::string describeLocation(const Fis& fis, const FisProblem& problem);
/// Throws FisError "fis 'name': problem" for the first problem of fisProblems().
void checkComplete(const Fis& fis);

/// .fis spellings of the method enums, and their inverses (nullopt if unknown).
std::string_view toString(FisType v);
std::string_view toString(AndMethod v);
std::string_view toString(OrMethod v);
std::string_view toString(ImpMethod v);
std::string_view toString(AggMethod v);
std::string_view toString(DefuzzMethod v);
std::optional<FisType> parseFisType(std::string_view s);
std::optional<AndMethod> parseAndMethod(std::string_view s);
std::optional<OrMethod> parseOrMethod(std::string_view s);
std::optional<ImpMethod> parseImpMethod(std::string_view s);
std::optional<AggMethod> parseAggMethod(std::string_view s);
std::optional<DefuzzMethod> parseDefuzzMethod(std::string_view s);
/// True for wtaver and wtsum.
bool isSugenoDefuzz(DefuzzMethod m);

}  // namespace inspect::fuzzy
