#include "shared/fuzzy/fis_writer.hpp"

#include <charconv>
#include <fstream>
#include <sstream>

#include "shared/fuzzy/fis_error.hpp"
#include "shared/util/number_text.hpp"

namespace inspect::fuzzy {

namespace {

// Shortest text that reads back to the same double.
std::string num(double v) { return util::shortest(v); }

void writeVariable(std::ostream& os, const char* kind, std::size_t index, const Variable& v) {
  os << '[' << kind << index + 1 << "]\n";
  os << "Name='" << v.name << "'\n";
  os << "Range=[" << num(v.min) << ' ' << num(v.max) << "]\n";
  os << "NumMFs=" << v.mfs.size() << '\n';
  for (std::size_t j = 0; j < v.mfs.size(); ++j) {
    const auto& mf = v.mfs[j];
    os << "MF" << j + 1 << "='" << mf.name << "':'" << mfTypeName(mf.type) << "',[";
    for (std::size_t k = 0; k < mf.params.size(); ++k) os << (k ? " " : "") << num(mf.params[k]);
    os << "]\n";
  }
  os << '\n';
}

}  // namespace

std::string formatFis(const Fis& fis) {
  std::ostringstream os;
  for (const auto& c : fis.comments) os << '%' << (c.empty() ? "" : " ") << c << '\n';
  if (!fis.comments.empty()) os << '\n';
  os << "[System]\n";
  os << "Name='" << fis.name << "'\n";
  os << "Type='" << toString(fis.type) << "'\n";
  os << "Version=" << fis.version << '\n';
  os << "NumInputs=" << fis.inputs.size() << '\n';
  os << "NumOutputs=" << fis.outputs.size() << '\n';
  os << "NumRules=" << fis.rules.size() << '\n';
  os << "AndMethod='" << toString(fis.and_method) << "'\n";
  os << "OrMethod='" << toString(fis.or_method) << "'\n";
  os << "ImpMethod='" << toString(fis.imp_method) << "'\n";
  os << "AggMethod='" << toString(fis.agg_method) << "'\n";
  os << "DefuzzMethod='" << toString(fis.defuzz_method) << "'\n";
  if (fis.disable_structural_checks) os << "DisableStructuralChecks=" << *fis.disable_structural_checks << '\n';
  os << '\n';
  for (std::size_t i = 0; i < fis.inputs.size(); ++i) writeVariable(os, "Input", i, fis.inputs[i]);
  for (std::size_t i = 0; i < fis.outputs.size(); ++i) writeVariable(os, "Output", i, fis.outputs[i]);
  os << "[Rules]\n";
  for (const auto& r : fis.rules) {
    for (std::size_t i = 0; i < r.antecedent.size(); ++i) os << (i ? " " : "") << r.antecedent[i];
    os << ',';
    for (int c : r.consequent) os << ' ' << c;
    os << " (" << num(r.weight) << ") : " << static_cast<int>(r.connection) << '\n';
  }
  return os.str();
}

void writeFisFile(const Fis& fis, const std::string& path) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw FisError(path + ": cannot open for writing");
  out << formatFis(fis);
  out.flush();
  if (!out) throw FisError(path + ": write failed");
}

}  // namespace inspect::fuzzy
