#pragma once
// Gains files: the eleven tracking gains (control::GainSet: Eq 15's kp', ki',
// kd', ke, kec, k1..k3 and Eq 12's a1..a3) as a commented flat YAML document,
// optionally naming the fuzzy system (.fis) the scalings belong to. Written by
// tuning sessions and the console's `gains export`, read by `gains import`;
// every number is written in its shortest exact form, so a file reads back to
// the same doubles.
#include <string>

#include "shared/config/config_node.hpp"
#include "shared/control/gain_set.hpp"
#include "shared/fuzzy/fis.hpp"

namespace inspect::config {

/// A gains file as read: the gains and the fuzzy system it names.
struct GainsFile {
  control::GainSet gains;
  std::string fis_path;  // the file's `fis:` resolved against the YAML's directory; "" if none
};

/// The YAML text: `comment` as '#' lines at the top (one per line of it), the
/// keys of control::kGainNames in order, and `fis: <fis_file>` unless empty.
std::string gainsYaml(const control::GainSet& g, const std::string& comment, const std::string& fis_file);

/// Reads a gains file. A missing key keeps its value from `defaults`; unknown
/// keys, values outside control::gainBounds and an unreadable file are
/// ConfigError "path: key: reason".
GainsFile loadGainsFile(const std::string& path, const control::GainSet& defaults);

/// Writes `yaml_path` and, beside it, <stem>.fis (the system `fis`), which the
/// YAML's `fis:` names. Refuses gains that fail control::validateGains.
/// Throws ConfigError naming the file that could not be written.
void exportGains(const control::GainSet& g, const fuzzy::Fis& fis, const std::string& yaml_path,
                 const std::string& comment);

/// loadGainsFile(), then, when the file names a .fis, reads it and checks it
/// has the fuzzy-PID shape (2 inputs, 3 outputs) into `*fis_out` (if not null;
/// left alone when the file names none). Throws ConfigError "yaml_path: fis: reason".
GainsFile importGains(const std::string& yaml_path, const control::GainSet& defaults, fuzzy::Fis* fis_out);

/// The gains as one compact JSON object, keys in control::kGainNames order
/// (the catalog's gains_json columns).
std::string gainsJson(const control::GainSet& g);

}  // namespace inspect::config
