#include "yaml_reader.hpp"

#include <charconv>
#include <cmath>
#include <limits>
#include <system_error>

namespace rail::core::detail {

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& x : items) out += (out.empty() ? "" : ", ") + x;
  return out;
}

void failAt(const std::string& file, const std::string& path, const std::string& what, int line) {
  std::string msg = file + ": " + (path.empty() ? std::string() : path + ": ") + what;
  if (line > 0) msg += " (line " + std::to_string(line) + ")";
  throw SceneError(msg);
}

MapReader::MapReader(const YAML::Node& node, std::string path, std::string file)
    : node_(node), path_(std::move(path)), file_(std::move(file)) {
  if (!node_.IsMap()) {
    const int line = node_.IsDefined() ? node_.Mark().line + 1 : 0;
    failAt(file_, path_, "must be a map of keys to values", line);
  }
}

// Const access: yaml-cpp's non-const operator[] would insert the key.
YAML::Node MapReader::lookup(const char* key) const {
  const YAML::Node& n = node_;
  return n[key];
}

int MapReader::lineOf(const char* key) const {
  const YAML::Node n = lookup(key);
  if (n.IsDefined() && n.Mark().line >= 0) return n.Mark().line + 1;
  return node_.Mark().line >= 0 ? node_.Mark().line + 1 : 0;
}

void MapReader::fail(const char* key, const std::string& what) const { failAt(file_, field(key), what, lineOf(key)); }

void MapReader::failHere(const std::string& what) const {
  failAt(file_, path_, what, node_.Mark().line >= 0 ? node_.Mark().line + 1 : 0);
}

bool MapReader::scalar(const char* key, std::string& text) {
  read_.insert(key);
  const YAML::Node n = lookup(key);
  if (!n.IsDefined() || n.IsNull()) return false;
  if (!n.IsScalar()) fail(key, "must be a single value, got a " + std::string(n.IsMap() ? "map" : "list"));
  text = n.Scalar();
  return true;
}

void MapReader::require(const char* key) {
  if (!has(key)) fail(key, "missing (required)");
}

namespace {
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
}  // namespace

void MapReader::number(const char* key, double& value) {
  std::string text;
  if (!scalar(key, text)) return;
  double v = 0.0;
  if (!parseNumber(text, v)) fail(key, "must be a number, got '" + text + "'");
  if (!std::isfinite(v)) fail(key, "must be a finite number, got " + text);
  value = v;
}

void MapReader::integer(const char* key, int& value) {
  std::string text;
  if (!scalar(key, text)) return;
  int v = 0;
  auto res = std::from_chars(text.data(), text.data() + text.size(), v);
  if (res.ec != std::errc() || res.ptr != text.data() + text.size())
    fail(key, "must be a whole number, got '" + text + "'");
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

void MapReader::numberList(const char* key, std::vector<double>& value) {
  const YAML::Node n = child(key);
  if (!n) return;
  if (!n.IsSequence()) fail(key, "must be a list of numbers");
  value.clear();
  for (std::size_t i = 0; i < n.size(); ++i) {
    const std::string item = field(key) + "[" + std::to_string(i) + "]";
    const int line = n[i].Mark().line >= 0 ? n[i].Mark().line + 1 : lineOf(key);
    double v = 0.0;
    if (!n[i].IsScalar() || !parseNumber(n[i].Scalar(), v) || !std::isfinite(v)) {
      failAt(file_, item, "must be a finite number, got '" + (n[i].IsScalar() ? n[i].Scalar() : "a list or map") + "'",
             line);
    }
    value.push_back(v);
  }
}

void MapReader::stringList(const char* key, std::vector<std::string>& value) {
  const YAML::Node n = child(key);
  if (!n) return;
  if (!n.IsSequence()) fail(key, "must be a list of names");
  value.clear();
  for (std::size_t i = 0; i < n.size(); ++i) {
    if (!n[i].IsScalar()) {
      failAt(file_, field(key) + "[" + std::to_string(i) + "]", "must be a name",
             n[i].Mark().line >= 0 ? n[i].Mark().line + 1 : lineOf(key));
    }
    value.push_back(n[i].Scalar());
  }
}

void MapReader::finish() const {
  for (const auto& kv : node_) {
    const std::string key = kv.first.as<std::string>();
    if (read_.count(key) == 0) {
      std::string known;
      for (const auto& k : read_) known += (known.empty() ? "" : ", ") + k;
      failAt(file_, field(key.c_str()), "unknown key (known here: " + known + ")",
             kv.first.Mark().line >= 0 ? kv.first.Mark().line + 1 : 0);
    }
  }
}

}  // namespace rail::core::detail
