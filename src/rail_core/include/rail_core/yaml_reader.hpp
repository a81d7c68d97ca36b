// The one reader of railsim's YAML input files (scene, track data, vehicle data). It knows where it is
// (file, field path, line), so every error has one form:
//   "<file>: <path>: <what> (line N)"
// where <what> ends in ", got <value>" when there is a value to show: the file's text in quotes when it is
// not of the expected kind, the number read when it is out of range.
#pragma once

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>

#include <cstdint>
#include <initializer_list>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <rail_contact/enum_words.hpp>

namespace rail::core {

using contact::Word;

// Throws a loader's own exception type with the message (a scene loader throws SceneError, the vehicle
// loader VehicleFileError). Without one, the reader throws std::runtime_error.
using RaiseError = void (*)(const std::string& message);

// "a, b, c".
std::string join(const std::vector<std::string>& items);

// "path.key", or "key" at the top level.
std::string joinPath(const std::string& path, const std::string& key);

// A node for a message: 'text' for a scalar, "a list", "a map", "nothing".
std::string describe(const YAML::Node& node);

// The 1-based line of a node in its file, 0 when unknown.
int lineOf(const YAML::Node& node);

// Throws "<file>: <path>: <what> (line N)"; an empty path or a line 0 is left out.
[[noreturn]] void failAt(const std::string& file, const std::string& path, const std::string& what, int line,
                         RaiseError raise = nullptr);

// Parses a YAML text, refusing a syntax error ("<file>: not valid YAML: ... (line N)"), a key given twice
// in one map (naming both lines) and an empty document.
YAML::Node parseYaml(const std::string& text, const std::string& file, RaiseError raise = nullptr);

// Reads and parses a file: "<path>: cannot open the file" when it cannot be read.
YAML::Node loadYamlFile(const std::string& path, RaiseError raise = nullptr);

// A YAML map being read. It remembers which keys were asked for, so that finish() refuses the rest as
// unknown, listing the known ones.
class MapReader {
 public:
  MapReader(const YAML::Node& node, std::string path, std::string file, RaiseError raise = nullptr);

  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }
  RaiseError raise() const { return raise_; }
  bool has(const char* key) const { return lookup(key).IsDefined() && !lookup(key).IsNull(); }
  std::string field(const char* key) const { return joinPath(path_, key); }
  // The node at key, undefined when absent; does not mark the key as read.
  YAML::Node node(const char* key) const { return lookup(key); }

  // Optional values: the target keeps its default when the key is absent or null.
  void number(const char* key, double& value);
  void integer(const char* key, int& value);
  void unsigned64(const char* key, std::uint64_t& value);
  void boolean(const char* key, bool& value);
  void string(const char* key, std::string& value);
  void numberList(const char* key, std::vector<double>& value);
  void stringList(const char* key, std::vector<std::string>& value);
  // One of `words` from the first (rail_contact/enum_words.hpp): "must be one of ..., got '...'" otherwise.
  template <class E, std::size_t N>
  void choice(const char* key, E& value, const Word<E> (&words)[N], std::size_t first = 0);

  // Required values: a missing key is "required key missing".
  double number(const char* key);
  std::string name(const char* key);  // a non-empty scalar
  bool boolean(const char* key);
  std::vector<int> integerList(const char* key);
  // A number in (0, max] or [0, max]; max is the physical upper bound, given with its unit. Values above it
  // (and inf) are refused, never clamped.
  double positive(const char* key, double max, const char* unit);
  double nonNegative(const char* key, double max, const char* unit);
  int positiveInteger(const char* key, int max);
  // A number with |value| <= max_abs; the optional one returns fallback when the key is absent.
  double bounded(const char* key, double max_abs, const char* unit);
  double optionalBounded(const char* key, double fallback, double max_abs, const char* unit);
  // A list of 3 numbers, each with |component| <= max_abs; the optional one is zero when absent.
  Eigen::Vector3d vector3(const char* key, double max_abs, const char* unit);
  Eigen::Vector3d optionalVector3(const char* key, double max_abs, const char* unit);

  // A nested map or list (marked as read); the node is returned for the caller to read.
  YAML::Node child(const char* key);
  YAML::Node requireChild(const char* key);
  // A required nested map, as a reader.
  MapReader map(const char* key);
  // A list (marked as read); an absent optional one is empty.
  YAML::Node list(const char* key, bool required);
  void require(const char* key);

  // Refuses keys that were not asked for: call after reading everything.
  void finish() const;

  // Throws "<file>: <path.key>: <what> (line N)".
  [[noreturn]] void fail(const char* key, const std::string& what) const;
  [[noreturn]] void failHere(const std::string& what) const;

  // Values that are not a key of this map (list items, table cells), with their own path.
  double numberAt(const YAML::Node& node, const std::string& path) const;
  double boundedAt(const YAML::Node& node, const std::string& path, double max_abs, const char* unit) const;
  Eigen::Vector3d vector3At(const YAML::Node& node, const std::string& path, double max_abs, const char* unit) const;
  [[noreturn]] void failAtNode(const YAML::Node& node, const std::string& path, const std::string& what) const;

 private:
  bool scalar(const char* key, std::string& text);  // false when absent or null
  YAML::Node lookup(const char* key) const;
  int lineOfKey(const char* key) const;

  YAML::Node node_;
  std::string path_;
  std::string file_;
  RaiseError raise_;
  std::set<std::string> read_;
};

template <class E, std::size_t N>
void MapReader::choice(const char* key, E& value, const Word<E> (&words)[N], std::size_t first) {
  std::string text;
  bool present = has(key);
  string(key, text);
  if (!present) return;
  std::string names;
  for (std::size_t i = first; i < N; ++i) {
    if (text == words[i].text) {
      value = words[i].value;
      return;
    }
    names += names.empty() ? "" : ", ";
    names += words[i].text;
  }
  fail(key, "must be one of " + names + ", got '" + text + "'");
}

}  // namespace rail::core
