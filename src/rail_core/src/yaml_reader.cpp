#include "rail_core/yaml_reader.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include <rail_contact/format.hpp>

#include "rail_core/yaml_duplicates.hpp"

namespace rail::core {

using contact::formatNumber;

namespace {

// Collections longer than this are named ("a list") rather than shown.
constexpr std::size_t kMaxShownCollection = 40;

// Reads a YAML number; YAML spells infinity and NaN with a dot. Returns false on anything else.
bool parseNumber(const std::string& text, double& v) {
  if (text == ".inf" || text == "+.inf" || text == ".Inf") {
    v = std::numeric_limits<double>::infinity();
  } else if (text == "-.inf" || text == "-.Inf") {
    v = -std::numeric_limits<double>::infinity();
  } else if (text == ".nan" || text == ".NaN" || text == "nan" || text == "NaN") {
    v = std::numeric_limits<double>::quiet_NaN();
  } else {
    const char* begin = text.data();
    const char* end = text.data() + text.size();
    if (begin != end && *begin == '+') ++begin;
    auto res = std::from_chars(begin, end, v);
    return res.ec == std::errc() && res.ptr == end && begin != end;
  }
  return true;
}

bool parseInteger(const std::string& text, int& v) {
  const char* begin = text.data();
  const char* end = text.data() + text.size();
  if (begin != end && *begin == '+') ++begin;
  auto res = std::from_chars(begin, end, v);
  return res.ec == std::errc() && res.ptr == end && begin != end;
}

std::string withUnit(double value, const char* unit) {
  return formatNumber(value) + (unit != nullptr && *unit != '\0' ? std::string(" ") + unit : std::string());
}

}  // namespace

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& x : items) out += (out.empty() ? "" : ", ") + x;
  return out;
}

std::string joinPath(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }

std::string describe(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing";
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  YAML::Emitter out;
  out << YAML::Flow << node;
  const std::string text = out.c_str();
  if (out.good() && text.size() <= kMaxShownCollection) return text;
  return node.IsSequence() ? "a list" : "a map";
}

int lineOf(const YAML::Node& node) { return node.IsDefined() && node.Mark().line >= 0 ? node.Mark().line + 1 : 0; }

void failAt(const std::string& file, const std::string& path, const std::string& what, int line, RaiseError raise) {
  std::string msg = file + ": " + (path.empty() ? std::string() : path + ": ") + what;
  if (line > 0) msg += " (line " + std::to_string(line) + ")";
  if (raise != nullptr) raise(msg);
  throw std::runtime_error(msg);
}

YAML::Node parseYaml(const std::string& text, const std::string& file, RaiseError raise) {
  YAML::Node doc;
  try {
    doc = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    failAt(file, "", "not valid YAML: " + e.msg, e.mark.line >= 0 ? e.mark.line + 1 : 0, raise);
  }
  if (const auto dup = findDuplicateKey(doc)) failAt(file, dup->field, dup->describe(), 0, raise);
  if (!doc.IsDefined() || doc.IsNull()) failAt(file, "", "is empty", 0, raise);
  return doc;
}

YAML::Node loadYamlFile(const std::string& path, RaiseError raise) {
  std::ifstream in(path);
  if (!in) failAt(path, "", "cannot open the file", 0, raise);
  std::stringstream text;
  text << in.rdbuf();
  return parseYaml(text.str(), path, raise);
}

MapReader::MapReader(const YAML::Node& node, std::string path, std::string file, RaiseError raise)
    : node_(node), path_(std::move(path)), file_(std::move(file)), raise_(raise) {
  if (!node_.IsMap())
    failAt(file_, path_, "must be a map of keys to values, got " + describe(node_), lineOf(node_), raise_);
}

// Const access: yaml-cpp's non-const operator[] would insert the key.
YAML::Node MapReader::lookup(const char* key) const {
  const YAML::Node& n = node_;
  return n[key];
}

int MapReader::lineOfKey(const char* key) const {
  const int line = lineOf(lookup(key));
  return line > 0 ? line : lineOf(node_);
}

void MapReader::fail(const char* key, const std::string& what) const {
  failAt(file_, field(key), what, lineOfKey(key), raise_);
}

void MapReader::failHere(const std::string& what) const { failAt(file_, path_, what, lineOf(node_), raise_); }

void MapReader::failAtNode(const YAML::Node& node, const std::string& path, const std::string& what) const {
  failAt(file_, path, what, lineOf(node) > 0 ? lineOf(node) : lineOf(node_), raise_);
}

bool MapReader::scalar(const char* key, std::string& text) {
  read_.insert(key);
  const YAML::Node n = lookup(key);
  if (!n.IsDefined() || n.IsNull()) return false;
  if (!n.IsScalar()) fail(key, "must be a single value, got " + describe(n));
  text = n.Scalar();
  return true;
}

void MapReader::require(const char* key) {
  read_.insert(key);
  if (!has(key)) fail(key, "required key missing");
}

void MapReader::number(const char* key, double& value) {
  read_.insert(key);
  if (has(key)) value = numberAt(lookup(key), field(key));
}

void MapReader::integer(const char* key, int& value) {
  std::string text;
  if (!scalar(key, text)) return;
  int v = 0;
  if (!parseInteger(text, v)) fail(key, "must be a whole number, got '" + text + "'");
  value = v;
}

void MapReader::unsigned64(const char* key, std::uint64_t& value) {
  std::string text;
  if (!scalar(key, text)) return;
  std::uint64_t v = 0;
  auto res = std::from_chars(text.data(), text.data() + text.size(), v);
  if (res.ec != std::errc() || res.ptr != text.data() + text.size())
    fail(key, "must be a whole number >= 0, got '" + text + "'");
  value = v;
}

void MapReader::boolean(const char* key, bool& value) {
  std::string t;
  if (!scalar(key, t)) return;
  if (t == "true" || t == "True" || t == "on" || t == "yes") {
    value = true;
  } else if (t == "false" || t == "False" || t == "off" || t == "no") {
    value = false;
  } else {
    fail(key, "must be true or false, got '" + t + "'");
  }
}

void MapReader::string(const char* key, std::string& value) { scalar(key, value); }

double MapReader::number(const char* key) {
  require(key);
  return numberAt(lookup(key), field(key));
}

std::string MapReader::name(const char* key) {
  require(key);
  std::string text;
  scalar(key, text);
  if (text.empty()) fail(key, "must be a name, got ''");
  return text;
}

bool MapReader::boolean(const char* key) {
  require(key);
  bool value = false;
  boolean(key, value);
  return value;
}

std::vector<int> MapReader::integerList(const char* key) {
  const YAML::Node n = list(key, true);
  std::vector<int> out;
  for (std::size_t i = 0; i < n.size(); ++i) {
    int v = 0;
    if (!n[i].IsScalar() || !parseInteger(n[i].Scalar(), v))
      failAtNode(n[i], field(key) + "[" + std::to_string(i) + "]", "must be a whole number, got " + describe(n[i]));
    out.push_back(v);
  }
  return out;
}

double MapReader::positive(const char* key, double max, const char* unit) {
  const double x = number(key);
  if (!(x > 0.0)) fail(key, "must be positive, got " + formatNumber(x));
  if (!(x <= max)) fail(key, "must be at most " + withUnit(max, unit) + ", got " + formatNumber(x));
  return x;
}

double MapReader::nonNegative(const char* key, double max, const char* unit) {
  const double x = number(key);
  if (!(x >= 0.0)) fail(key, "must not be negative, got " + formatNumber(x));
  if (!(x <= max)) fail(key, "must be at most " + withUnit(max, unit) + ", got " + formatNumber(x));
  return x;
}

int MapReader::positiveInteger(const char* key, int max) {
  require(key);
  int x = 0;
  integer(key, x);
  if (x <= 0) fail(key, "must be positive, got " + std::to_string(x));
  if (x > max) fail(key, "must be at most " + std::to_string(max) + ", got " + std::to_string(x));
  return x;
}

double MapReader::bounded(const char* key, double max_abs, const char* unit) {
  require(key);
  return boundedAt(lookup(key), field(key), max_abs, unit);
}

double MapReader::optionalBounded(const char* key, double fallback, double max_abs, const char* unit) {
  read_.insert(key);
  return has(key) ? boundedAt(lookup(key), field(key), max_abs, unit) : fallback;
}

Eigen::Vector3d MapReader::vector3(const char* key, double max_abs, const char* unit) {
  require(key);
  return vector3At(lookup(key), field(key), max_abs, unit);
}

Eigen::Vector3d MapReader::optionalVector3(const char* key, double max_abs, const char* unit) {
  read_.insert(key);
  return has(key) ? vector3At(lookup(key), field(key), max_abs, unit) : Eigen::Vector3d::Zero();
}

double MapReader::numberAt(const YAML::Node& node, const std::string& path) const {
  if (!node.IsScalar()) failAtNode(node, path, "must be a number, got " + describe(node));
  double v = 0.0;
  if (!parseNumber(node.Scalar(), v)) failAtNode(node, path, "must be a number, got " + describe(node));
  if (!std::isfinite(v)) failAtNode(node, path, "must be a finite number, got " + node.Scalar());
  return v;
}

double MapReader::boundedAt(const YAML::Node& node, const std::string& path, double max_abs, const char* unit) const {
  const double v = numberAt(node, path);
  if (!(std::abs(v) <= max_abs))
    failAtNode(node, path, "magnitude must be at most " + withUnit(max_abs, unit) + ", got " + formatNumber(v));
  return v;
}

Eigen::Vector3d MapReader::vector3At(const YAML::Node& node, const std::string& path, double max_abs,
                                     const char* unit) const {
  if (!node.IsSequence() || node.size() != 3)
    failAtNode(node, path, "must be a list of 3 numbers, got " + describe(node));
  Eigen::Vector3d v;
  for (std::size_t k = 0; k < 3; ++k)
    v[static_cast<int>(k)] = boundedAt(node[k], path + "[" + std::to_string(k) + "]", max_abs, unit);
  return v;
}

YAML::Node MapReader::child(const char* key) {
  read_.insert(key);
  const YAML::Node n = lookup(key);
  if (!n.IsDefined() || n.IsNull()) return YAML::Node(YAML::NodeType::Undefined);
  return n;
}

YAML::Node MapReader::requireChild(const char* key) {
  require(key);
  return child(key);
}

MapReader MapReader::map(const char* key) { return MapReader(requireChild(key), field(key), file_, raise_); }

YAML::Node MapReader::list(const char* key, bool required) {
  if (required) require(key);
  const YAML::Node n = child(key);
  if (!n) return YAML::Node(YAML::NodeType::Sequence);
  if (!n.IsSequence()) fail(key, "must be a list, got " + describe(n));
  return n;
}

void MapReader::numberList(const char* key, std::vector<double>& value) {
  const YAML::Node n = child(key);
  if (!n) return;
  if (!n.IsSequence()) fail(key, "must be a list of numbers, got " + describe(n));
  value.clear();
  for (std::size_t i = 0; i < n.size(); ++i)
    value.push_back(numberAt(n[i], field(key) + "[" + std::to_string(i) + "]"));
}

void MapReader::stringList(const char* key, std::vector<std::string>& value) {
  const YAML::Node n = child(key);
  if (!n) return;
  if (!n.IsSequence()) fail(key, "must be a list of names, got " + describe(n));
  value.clear();
  for (std::size_t i = 0; i < n.size(); ++i) {
    if (!n[i].IsScalar())
      failAtNode(n[i], field(key) + "[" + std::to_string(i) + "]", "must be a name, got " + describe(n[i]));
    value.push_back(n[i].Scalar());
  }
}

void MapReader::finish() const {
  for (const auto& kv : node_) {
    const std::string key = kv.first.as<std::string>();
    if (read_.count(key) == 0) {
      std::string known;
      for (const auto& k : read_) known += (known.empty() ? "" : ", ") + k;
      failAt(file_, field(key.c_str()), "unknown key (known here: " + known + ")", lineOf(kv.first), raise_);
    }
  }
}

}  // namespace rail::core
