#pragma once
// Checked reading of YAML configuration: every value is validated against its
// range, and every error names the file, the key and the reason.
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace inspect::config {

/// Startup/configuration error; main() prints what() and exits non-zero.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A YAML mapping being read. Tracks which keys were read so that unknown
/// (e.g. misspelt) keys can be reported by checkKnown().
class ConfigNode {
 public:
  /// Parses a file; throws ConfigError naming the file and line on syntax errors.
  static ConfigNode loadFile(const std::string& path);
  /// Parses text (for tests); `name` stands in for the file name in messages.
  static ConfigNode loadString(const std::string& text, const std::string& name);

  bool has(const std::string& key) const;
  /// A required nested mapping.
  ConfigNode child(const std::string& key) const;
  /// An optional nested mapping (empty mapping when absent).
  ConfigNode optChild(const std::string& key) const;
  /// A list of mappings (empty when absent).
  std::vector<ConfigNode> children(const std::string& key) const;

  /// Optional number with default, checked to lie in [min, max].
  double number(const std::string& key, double def, double min, double max) const;
  /// Required number in [min, max].
  double requireNumber(const std::string& key, double min, double max) const;
  /// Optional integer with default, in [min, max].
  long integer(const std::string& key, long def, long min, long max) const;
  bool boolean(const std::string& key, bool def) const;
  std::string string(const std::string& key, const std::string& def) const;
  std::string requireString(const std::string& key) const;
  /// Optional string that must be one of `choices`.
  std::string oneOf(const std::string& key, const std::string& def, const std::vector<std::string>& choices) const;
  /// A list of numbers; when `size` >= 0 the list must have exactly that many.
  std::vector<double> numbers(const std::string& key, int size = -1) const;
  /// An optional list of strings (empty when absent).
  std::vector<std::string> strings(const std::string& key) const;

  /// Throws ConfigError for keys in this mapping (and nested ones read) never read.
  void checkKnown() const;
  /// Throws ConfigError "file: key: reason".
  [[noreturn]] void fail(const std::string& key, const std::string& reason) const;

  const std::string& file() const { return state_->file; }
  /// Dotted path of a key below this node, e.g. "limits.max_v_m_s".
  std::string path(const std::string& key) const;

 private:
  struct State {
    YAML::Node node;
    std::string file;
    std::string prefix;
    std::vector<std::string> used;
    std::vector<std::shared_ptr<State>> kids;
  };
  explicit ConfigNode(std::shared_ptr<State> s) : state_(std::move(s)) {}
  ConfigNode makeChild(const YAML::Node& n, const std::string& key) const;
  YAML::Node get(const std::string& key) const;
  void markUsed(const std::string& key) const;
  static void checkKnownRec(const State& s);
  std::shared_ptr<State> state_;
};

}  // namespace inspect::config
