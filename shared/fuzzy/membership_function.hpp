#pragma once
// Membership functions of the MATLAB Fuzzy Logic Toolbox, as value types:
// the set is closed (it is the .fis vocabulary), so a tagged struct with one
// switch keeps a Fis comparable, copyable and free of heap-owned objects.
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace inspect::fuzzy {

/// MATLAB membership-function types (the .fis names are given by mfTypeName()).
enum class MfType {
  kTrimf,     ///< [a b c]
  kTrapmf,    ///< [a b c d]
  kGaussmf,   ///< [sigma c]
  kGauss2mf,  ///< [sigma1 c1 sigma2 c2]
  kGbellmf,   ///< [a b c]
  kSigmf,     ///< [a c]
  kDsigmf,    ///< [a1 c1 a2 c2]  |sigmf1 - sigmf2|
  kPsigmf,    ///< [a1 c1 a2 c2]  sigmf1 * sigmf2
  kSmf,       ///< [a b]
  kZmf,       ///< [a b]
  kPimf,      ///< [a b c d]  smf(a,b) * zmf(c,d)
  kConstant,  ///< [z]  Sugeno output only
  kLinear,    ///< [p1 .. pn r]  Sugeno output only: p . x + r
};

/// One named term of a variable: `MF1='NB':'gaussmf',[0.4247 -3]`.
struct MembershipFunction {
  std::string name;
  MfType type = MfType::kTrimf;
  std::vector<double> params;

  bool operator==(const MembershipFunction&) const = default;
};

/// The .fis spelling of a type ("trimf", ...).
std::string_view mfTypeName(MfType type);
/// The type for a .fis spelling; nullopt when unknown.
std::optional<MfType> parseMfType(std::string_view name);
/// True for the Sugeno output types (constant, linear).
bool isSugenoOutputType(MfType type);
/// Number of parameters the type needs; `num_inputs` matters only for linear.
std::size_t mfParamCount(MfType type, std::size_t num_inputs);
/// Why the parameters are unusable (count, ordering, zero widths), or empty
/// when they are fine. `num_inputs` matters only for linear.
std::string mfParamProblem(MfType type, std::span<const double> params, std::size_t num_inputs);

/// Degree of membership of x (MATLAB's formulas). For constant and linear
/// (Sugeno outputs) use sugenoOutput() instead; here they return 0.
double mfValue(MfType type, std::span<const double> params, double x) noexcept;
/// Crisp value of a Sugeno output term for the given inputs.
double sugenoOutput(MfType type, std::span<const double> params, std::span<const double> inputs) noexcept;

}  // namespace inspect::fuzzy
