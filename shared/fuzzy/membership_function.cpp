#include "shared/fuzzy/membership_function.hpp"
#include "shared/util/number_text.hpp"

#include <array>
#include <cmath>
#include <utility>

namespace inspect::fuzzy {

namespace {

struct TypeName {
  MfType type;
  std::string_view name;
};

constexpr std::array<TypeName, 13> kTypeNames{{
    {MfType::kTrimf, "trimf"},
    {MfType::kTrapmf, "trapmf"},
    {MfType::kGaussmf, "gaussmf"},
    {MfType::kGauss2mf, "gauss2mf"},
    {MfType::kGbellmf, "gbellmf"},
    {MfType::kSigmf, "sigmf"},
    {MfType::kDsigmf, "dsigmf"},
    {MfType::kPsigmf, "psigmf"},
    {MfType::kSmf, "smf"},
    {MfType::kZmf, "zmf"},
    {MfType::kPimf, "pimf"},
    {MfType::kConstant, "constant"},
    {MfType::kLinear, "linear"},
}};

double gauss(double sigma, double c, double x) noexcept {
  const double d = x - c;
  return std::exp(-(d * d) / (2.0 * sigma * sigma));
}

double sigmoid(double a, double c, double x) noexcept { return 1.0 / (1.0 + std::exp(-a * (x - c))); }

// MATLAB smf.m: quadratic spline from 0 at a to 1 at b.
double sShape(double a, double b, double x) noexcept {
  if (x <= a) return 0.0;
  if (x >= b) return 1.0;
  const double mid = 0.5 * (a + b);
  if (x <= mid) {
    const double t = (x - a) / (b - a);
    return 2.0 * t * t;
  }
  const double t = (x - b) / (b - a);
  return 1.0 - 2.0 * t * t;
}

// MATLAB zmf.m: mirror image of smf.
double zShape(double a, double b, double x) noexcept {
  if (x <= a) return 1.0;
  if (x >= b) return 0.0;
  const double mid = 0.5 * (a + b);
  if (x <= mid) {
    const double t = (x - a) / (b - a);
    return 1.0 - 2.0 * t * t;
  }
  const double t = (x - b) / (b - a);
  return 2.0 * t * t;
}

std::string fmt(double v) { return util::fmtShort(v, 6); }

}  // namespace

std::string_view mfTypeName(MfType type) {
  for (const auto& t : kTypeNames) {
    if (t.type == type) return t.name;
  }
  return "?";
}

std::optional<MfType> parseMfType(std::string_view name) {
  for (const auto& t : kTypeNames) {
    if (t.name == name) return t.type;
  }
  return std::nullopt;
}

bool isSugenoOutputType(MfType type) { return type == MfType::kConstant || type == MfType::kLinear; }

std::size_t mfParamCount(MfType type, std::size_t num_inputs) {
  switch (type) {
    case MfType::kTrimf: return 3;
    case MfType::kTrapmf: return 4;
    case MfType::kGaussmf: return 2;
    case MfType::kGauss2mf: return 4;
    case MfType::kGbellmf: return 3;
    case MfType::kSigmf: return 2;
    case MfType::kDsigmf: return 4;
    case MfType::kPsigmf: return 4;
    case MfType::kSmf: return 2;
    case MfType::kZmf: return 2;
    case MfType::kPimf: return 4;
    case MfType::kConstant: return 1;
    case MfType::kLinear: return num_inputs + 1;
  }
  return 0;
}

std::string mfParamProblem(MfType type, std::span<const double> p, std::size_t num_inputs) {
  const std::string tname(mfTypeName(type));
  const std::size_t need = mfParamCount(type, num_inputs);
  if (p.size() != need) {
    return tname + " needs " + std::to_string(need) + " parameter" + (need == 1 ? "" : "s") + ", got " +
           std::to_string(p.size());
  }
  for (double v : p) {
    if (!std::isfinite(v)) return tname + ": parameters must be finite numbers";
  }
  switch (type) {
    case MfType::kTrimf:
      if (!(p[0] <= p[1] && p[1] <= p[2])) {
        return "trimf [a b c] needs a <= b <= c, got [" + fmt(p[0]) + " " + fmt(p[1]) + " " + fmt(p[2]) + "]";
      }
      break;
    case MfType::kTrapmf:
      if (!(p[0] <= p[1] && p[1] <= p[2] && p[2] <= p[3])) {
        return "trapmf [a b c d] needs a <= b <= c <= d, got [" + fmt(p[0]) + " " + fmt(p[1]) + " " + fmt(p[2]) +
               " " + fmt(p[3]) + "]";
      }
      break;
    case MfType::kGaussmf:
      if (!(p[0] > 0)) return "gaussmf [sigma c] needs sigma > 0, got " + fmt(p[0]);
      break;
    case MfType::kGauss2mf:
      if (!(p[0] > 0) || !(p[2] > 0)) {
        return "gauss2mf [sigma1 c1 sigma2 c2] needs both sigmas > 0, got " + fmt(p[0]) + " and " + fmt(p[2]);
      }
      break;
    case MfType::kGbellmf:
      if (p[0] == 0) return "gbellmf [a b c] needs a != 0";
      if (!(p[1] > 0)) return "gbellmf [a b c] needs b > 0, got " + fmt(p[1]);
      break;
    case MfType::kSmf:
    case MfType::kZmf:
      if (!(p[0] < p[1])) return tname + " [a b] needs a < b, got [" + fmt(p[0]) + " " + fmt(p[1]) + "]";
      break;
    case MfType::kPimf:
      if (!(p[0] < p[1]) || !(p[2] < p[3])) {
        return "pimf [a b c d] needs a < b and c < d, got [" + fmt(p[0]) + " " + fmt(p[1]) + " " + fmt(p[2]) + " " +
               fmt(p[3]) + "]";
      }
      break;
    case MfType::kSigmf:
    case MfType::kDsigmf:
    case MfType::kPsigmf:
    case MfType::kConstant:
    case MfType::kLinear:
      break;
  }
  return {};
}

double mfValue(MfType type, std::span<const double> p, double x) noexcept {
  switch (type) {
    case MfType::kTrimf: {
      // MATLAB trimf.m: the peak wins even for a vertical side (a == b or b == c).
      const double a = p[0], b = p[1], c = p[2];
      if (x == b) return 1.0;
      if (x <= a || x >= c) return 0.0;
      if (x < b) return (x - a) / (b - a);
      return (c - x) / (c - b);
    }
    case MfType::kTrapmf: {
      // MATLAB trapmf.m: min of a rising and a falling shoulder.
      const double a = p[0], b = p[1], c = p[2], d = p[3];
      double y1 = 0.0;
      if (x >= b) {
        y1 = 1.0;
      } else if (x >= a && a != b) {
        y1 = (x - a) / (b - a);
      }
      double y2 = 0.0;
      if (x <= c) {
        y2 = 1.0;
      } else if (x <= d && c != d) {
        y2 = (d - x) / (d - c);
      }
      return y1 < y2 ? y1 : y2;
    }
    case MfType::kGaussmf: return gauss(p[0], p[1], x);
    case MfType::kGauss2mf: {
      const double y1 = x <= p[1] ? gauss(p[0], p[1], x) : 1.0;
      const double y2 = x >= p[3] ? gauss(p[2], p[3], x) : 1.0;
      return y1 * y2;
    }
    case MfType::kGbellmf: {
      const double t = (x - p[2]) / p[0];
      return 1.0 / (1.0 + std::pow(t * t, p[1]));
    }
    case MfType::kSigmf: return sigmoid(p[0], p[1], x);
    case MfType::kDsigmf: return std::abs(sigmoid(p[0], p[1], x) - sigmoid(p[2], p[3], x));
    case MfType::kPsigmf: return sigmoid(p[0], p[1], x) * sigmoid(p[2], p[3], x);
    case MfType::kSmf: return sShape(p[0], p[1], x);
    case MfType::kZmf: return zShape(p[0], p[1], x);
    case MfType::kPimf: return sShape(p[0], p[1], x) * zShape(p[2], p[3], x);
    case MfType::kConstant:
    case MfType::kLinear: return 0.0;
  }
  return 0.0;
}

double sugenoOutput(MfType type, std::span<const double> p, std::span<const double> inputs) noexcept {
  if (type == MfType::kConstant) return p[0];
  if (type == MfType::kLinear) {
    double z = p[inputs.size()];
    for (std::size_t i = 0; i < inputs.size(); ++i) z += p[i] * inputs[i];
    return z;
  }
  return 0.0;
}

}  // namespace inspect::fuzzy
