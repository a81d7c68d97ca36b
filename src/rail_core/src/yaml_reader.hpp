// A small reader over yaml-cpp nodes that knows where it is (file, field path, line), so each error names
// the file and the field. Used by the scene loader; internal to rail_core.
#pragma once

#include <yaml-cpp/yaml.h>

#include <functional>
#include <initializer_list>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "rail_core/scene_loader.hpp"

namespace rail::core::detail {

// "a, b, c".
std::string join(const std::vector<std::string>& items);

// A YAML map being read: remembers which keys were read so the rest can be refused as unknown.
class MapReader {
 public:
  MapReader(const YAML::Node& node, std::string path, std::string file);

  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }
  bool has(const char* key) const { return lookup(key).IsDefined() && !lookup(key).IsNull(); }
  std::string field(const char* key) const { return path_.empty() ? key : path_ + "." + key; }

  // Optional values: the target keeps its default when the key is absent.
  void number(const char* key, double& value);
  void integer(const char* key, int& value);
  void unsigned64(const char* key, std::uint64_t& value);
  void boolean(const char* key, bool& value);
  void string(const char* key, std::string& value);
  void numberList(const char* key, std::vector<double>& value);
  void stringList(const char* key, std::vector<std::string>& value);
  template <typename E>
  void choice(const char* key, E& value, std::initializer_list<std::pair<const char*, E>> choices);

  // A nested map or list (marked as read); the node is returned for the caller to read.
  YAML::Node child(const char* key);
  YAML::Node requireChild(const char* key);
  void require(const char* key);

  // Refuses keys that were not read: call after reading everything.
  void finish() const;

  // Throws SceneError "<file>: <path.key>: <what> (line N)".
  [[noreturn]] void fail(const char* key, const std::string& what) const;
  [[noreturn]] void failHere(const std::string& what) const;

 private:
  bool scalar(const char* key, std::string& text);  // false when absent or null
  YAML::Node lookup(const char* key) const;
  int lineOf(const char* key) const;

  YAML::Node node_;
  std::string path_;
  std::string file_;
  std::set<std::string> read_;
};

[[noreturn]] void failAt(const std::string& file, const std::string& path, const std::string& what, int line);

template <typename E>
void MapReader::choice(const char* key, E& value, std::initializer_list<std::pair<const char*, E>> choices) {
  std::string text;
  bool present = has(key);
  string(key, text);
  if (!present) return;
  std::string names;
  for (const auto& c : choices) {
    if (text == c.first) {
      value = c.second;
      return;
    }
    names += names.empty() ? "" : ", ";
    names += c.first;
  }
  fail(key, "must be one of " + names + ", got '" + text + "'");
}

}  // namespace rail::core::detail
