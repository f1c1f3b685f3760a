#include "shared/config/gains_file.hpp"

#include <charconv>
#include <cmath>
#include <filesystem>
#include <sstream>

#include <nlohmann/json.hpp>

#include "shared/control/fuzzy_pid.hpp"
#include "shared/fuzzy/fis_error.hpp"
#include "shared/fuzzy/fis_reader.hpp"
#include "shared/fuzzy/fis_writer.hpp"
#include "shared/util/file_util.hpp"
#include "shared/util/number_text.hpp"

namespace inspect::config {

namespace {

namespace fs = std::filesystem;

// Shortest text that reads back to the same double; YAML's spellings otherwise.
std::string num(double v) {
  if (std::isnan(v)) return ".nan";
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  return util::shortest(v);
}

// What each key is, for the file's readers (same order as control::kGainNames).
const char* meaning(const std::string& name) {
  if (name == "kp") return "kp', base proportional gain of the wheel loop (Eq 15)";
  if (name == "ki") return "ki', base integral gain (Eq 15)";
  if (name == "kd") return "kd', base derivative gain (Eq 15)";
  if (name == "ke") return "error scaling into the fuzzy universe (Eq 15)";
  if (name == "kec") return "error-rate scaling (Eq 15)";
  if (name == "k1") return "kpx scaling (Eq 15)";
  if (name == "k2") return "kix scaling (Eq 15)";
  if (name == "k3") return "kdx scaling (Eq 15)";
  if (name == "a1") return "x error -> speed (Eq 12)";
  if (name == "a2") return "heading error -> yaw rate (Eq 12)";
  if (name == "a3") return "lateral error -> yaw rate (Eq 12)";
  return "";
}

std::string stemFisPath(const std::string& yaml_path) {
  fs::path p(yaml_path);
  p.replace_extension(".fis");
  return p.string();
}

}  // namespace

std::string gainsYaml(const control::GainSet& g, const std::string& comment, const std::string& fis_file) {
  std::ostringstream os;
  if (!comment.empty()) {
    std::istringstream lines(comment);
    std::string line;
    while (std::getline(lines, line)) os << (line.empty() ? "#" : "# " + line) << "\n";
  }
  for (const char* name : control::kGainNames) {
    double lo = 0, hi = 0;
    control::gainBounds(name, lo, hi);
    std::string key = std::string(name) + ": " + num(control::gainValue(g, name));
    if (key.size() < 28) key.resize(28, ' ');
    os << key << "# " << meaning(name) << "; [" << num(lo) << ", " << num(hi) << "]\n";
  }
  if (!fis_file.empty()) {
    std::string quoted = "\"";
    for (const char c : fis_file) quoted += (c == '"' || c == '\\') ? std::string("\\") + c : std::string(1, c);
    os << "fis: " << quoted << "\"  # the fuzzy system these scalings belong to\n";
  }
  return os.str();
}

GainsFile loadGainsFile(const std::string& path, const control::GainSet& defaults) {
  const ConfigNode root = ConfigNode::loadFile(path);
  GainsFile out;
  out.gains = defaults;
  for (const char* name : control::kGainNames) {
    double lo = 0, hi = 0;
    control::gainBounds(name, lo, hi);
    double* v = control::gainByName(out.gains, name);
    *v = root.number(name, *v, lo, hi);
  }
  const std::string fis = root.string("fis", "");
  root.checkKnown();
  // Defaults the file did not override are checked too: the result is always usable.
  if (const std::string err = control::validateGains(out.gains); !err.empty())
    throw ConfigError(path + ": " + err + " (a default the file does not set)");
  if (!fis.empty()) {
    const fs::path p(fis);
    out.fis_path = p.is_absolute() ? p.string() : (fs::path(path).parent_path() / p).string();
  }
  return out;
}

void exportGains(const control::GainSet& g, const fuzzy::Fis& fis, const std::string& yaml_path,
                 const std::string& comment) {
  if (const std::string err = control::validateGains(g); !err.empty())
    throw ConfigError(yaml_path + ": refusing to write invalid gains: " + err);
  if (fs::path(yaml_path).extension() == ".fis")
    throw ConfigError(yaml_path + ": a gains file must not end in .fis (its fuzzy system is written beside it as <stem>.fis)");
  const std::string fis_path = stemFisPath(yaml_path);
  // The .fis first: the YAML never names a file that is not there.
  try {
    fuzzy::writeFisFile(fis, fis_path);
  } catch (const fuzzy::FisError& e) {
    throw ConfigError(e.what());  // names the file
  }
  const std::string text = gainsYaml(g, comment, fs::path(fis_path).filename().string());
  if (const std::string err = writeFileAtomically(yaml_path, text); !err.empty()) throw ConfigError(err);
}

GainsFile importGains(const std::string& yaml_path, const control::GainSet& defaults, fuzzy::Fis* fis_out) {
  GainsFile out = loadGainsFile(yaml_path, defaults);
  if (out.fis_path.empty()) return out;
  try {
    fuzzy::Fis fis = fuzzy::readFisFile(out.fis_path);
    control::FuzzyGainScheduler check(fis, false);  // throws unless 2 inputs and 3 outputs
    if (fis_out) *fis_out = std::move(fis);
  } catch (const fuzzy::FisError& e) {
    throw ConfigError(yaml_path + ": fis: " + e.what());
  }
  return out;
}

std::string gainsJson(const control::GainSet& g) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (const char* name : control::kGainNames) {
    const double v = control::gainValue(g, name);
    j[name] = std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
  }
  return j.dump();
}

}  // namespace inspect::config
