#include "shared/config/config_node.hpp"
#include "shared/util/number_text.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

namespace inspect::config {

namespace {
std::string fmtNum(double v) { return util::significant(v, 12); }  // ranges like [1024, 67108864] print exactly
}  // namespace

ConfigNode ConfigNode::loadFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open file");
  std::stringstream ss;
  ss << in.rdbuf();
  return loadString(ss.str(), path);
}

ConfigNode ConfigNode::loadString(const std::string& text, const std::string& name) {
  auto s = std::make_shared<State>();
  s->file = name;
  try {
    s->node = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(name + ":" + std::to_string(e.mark.line + 1) + ": YAML syntax error: " + e.msg);
  }
  if (s->node.IsNull()) s->node = YAML::Node(YAML::NodeType::Map);
  if (!s->node.IsMap()) throw ConfigError(name + ": the top level must be a mapping of keys to values");
  return ConfigNode(s);
}

std::string ConfigNode::path(const std::string& key) const {
  return state_->prefix.empty() ? key : state_->prefix + "." + key;
}

void ConfigNode::fail(const std::string& key, const std::string& reason) const {
  throw ConfigError(state_->file + ": " + path(key) + ": " + reason);
}

void ConfigNode::markUsed(const std::string& key) const {
  if (std::find(state_->used.begin(), state_->used.end(), key) == state_->used.end()) state_->used.push_back(key);
}

YAML::Node ConfigNode::get(const std::string& key) const {
  markUsed(key);
  if (!state_->node.IsMap()) return YAML::Node();
  return state_->node[key];
}

bool ConfigNode::has(const std::string& key) const {
  return state_->node.IsMap() && state_->node[key] && !state_->node[key].IsNull();
}

ConfigNode ConfigNode::makeChild(const YAML::Node& n, const std::string& key) const {
  auto s = std::make_shared<State>();
  s->node = n;
  s->file = state_->file;
  s->prefix = path(key);
  state_->kids.push_back(s);
  return ConfigNode(s);
}

ConfigNode ConfigNode::child(const std::string& key) const {
  YAML::Node n = get(key);
  if (!n || n.IsNull()) fail(key, "required section is missing");
  if (!n.IsMap()) fail(key, "must be a mapping of keys to values");
  return makeChild(n, key);
}

ConfigNode ConfigNode::optChild(const std::string& key) const {
  YAML::Node n = get(key);
  if (!n || n.IsNull()) return makeChild(YAML::Node(YAML::NodeType::Map), key);
  if (!n.IsMap()) fail(key, "must be a mapping of keys to values");
  return makeChild(n, key);
}

std::vector<ConfigNode> ConfigNode::children(const std::string& key) const {
  YAML::Node n = get(key);
  std::vector<ConfigNode> out;
  if (!n || n.IsNull()) return out;
  if (!n.IsSequence()) fail(key, "must be a list");
  for (std::size_t i = 0; i < n.size(); ++i) {
    if (!n[i].IsMap()) fail(key + "[" + std::to_string(i) + "]", "must be a mapping of keys to values");
    out.push_back(makeChild(n[i], key + "[" + std::to_string(i) + "]"));
  }
  return out;
}

double ConfigNode::requireNumber(const std::string& key, double min, double max) const {
  YAML::Node n = get(key);
  if (!n || n.IsNull()) fail(key, "required value is missing");
  if (!n.IsScalar()) fail(key, "must be a number");
  double v = 0;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    fail(key, "'" + n.Scalar() + "' is not a number");
  }
  if (!std::isfinite(v)) fail(key, "must be finite");
  if (v < min || v > max) fail(key, fmtNum(v) + " is out of range [" + fmtNum(min) + ", " + fmtNum(max) + "]");
  return v;
}

double ConfigNode::number(const std::string& key, double def, double min, double max) const {
  if (!has(key)) {
    markUsed(key);
    return def;
  }
  return requireNumber(key, min, max);
}

long ConfigNode::integer(const std::string& key, long def, long min, long max) const {
  if (!has(key)) {
    markUsed(key);
    return def;
  }
  const double v = requireNumber(key, static_cast<double>(min), static_cast<double>(max));
  if (v != std::floor(v)) fail(key, fmtNum(v) + " is not a whole number");
  return static_cast<long>(v);
}

bool ConfigNode::boolean(const std::string& key, bool def) const {
  YAML::Node n = get(key);
  if (!n || n.IsNull()) return def;
  try {
    return n.as<bool>();
  } catch (const YAML::Exception&) {
    fail(key, "'" + (n.IsScalar() ? n.Scalar() : std::string("?")) + "' is not true or false");
  }
}

std::string ConfigNode::string(const std::string& key, const std::string& def) const {
  YAML::Node n = get(key);
  if (!n || n.IsNull()) return def;
  if (!n.IsScalar()) fail(key, "must be a string");
  return n.Scalar();
}

std::string ConfigNode::requireString(const std::string& key) const {
  if (!has(key)) fail(key, "required value is missing");
  return string(key, "");
}

std::string ConfigNode::oneOf(const std::string& key, const std::string& def,
                              const std::vector<std::string>& choices) const {
  const std::string v = string(key, def);
  if (std::find(choices.begin(), choices.end(), v) != choices.end()) return v;
  std::string list;
  for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
  fail(key, "'" + v + "' is not one of: " + list);
}

std::vector<double> ConfigNode::numbers(const std::string& key, int size) const {
  YAML::Node n = get(key);
  std::vector<double> out;
  if (!n || n.IsNull()) {
    if (size > 0) fail(key, "required list of " + std::to_string(size) + " numbers is missing");
    return out;
  }
  if (!n.IsSequence()) fail(key, "must be a list of numbers");
  for (std::size_t i = 0; i < n.size(); ++i) {
    try {
      const double v = n[i].as<double>();
      if (!std::isfinite(v)) fail(key, "element " + std::to_string(i) + " must be finite");
      out.push_back(v);
    } catch (const YAML::Exception&) {
      fail(key, "element " + std::to_string(i) + " is not a number");
    }
  }
  if (size >= 0 && static_cast<int>(out.size()) != size)
    fail(key, "must have exactly " + std::to_string(size) + " numbers, has " + std::to_string(out.size()));
  return out;
}

std::vector<std::string> ConfigNode::strings(const std::string& key) const {
  YAML::Node n = get(key);
  std::vector<std::string> out;
  if (!n || n.IsNull()) return out;
  if (!n.IsSequence()) fail(key, "must be a list of strings");
  for (std::size_t i = 0; i < n.size(); ++i) {
    if (!n[i].IsScalar()) fail(key, "element " + std::to_string(i) + " must be a string");
    out.push_back(n[i].Scalar());
  }
  return out;
}

void ConfigNode::checkKnownRec(const State& s) {
  if (s.node.IsMap()) {
    for (const auto& kv : s.node) {
      const std::string k = kv.first.Scalar();
      if (std::find(s.used.begin(), s.used.end(), k) == s.used.end()) {
        const std::string p = s.prefix.empty() ? k : s.prefix + "." + k;
        throw ConfigError(s.file + ": " + p + ": unknown key (misspelt, or not used by this program)");
      }
    }
  }
  for (const auto& k : s.kids) checkKnownRec(*k);
}

void ConfigNode::checkKnown() const { checkKnownRec(*state_); }

}  // namespace inspect::config
