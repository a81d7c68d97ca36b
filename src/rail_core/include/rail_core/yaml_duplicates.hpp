// yaml-cpp keeps the first of two equal keys in a map without a word. Every YAML file railsim reads (scene,
// track data, vehicle data) is checked with this so that a key given twice is refused, naming both lines.
#pragma once

#include <yaml-cpp/yaml.h>

#include <optional>
#include <string>

namespace rail::core {

struct DuplicateKey {
  std::string field;    // dotted path with list indices, e.g. "bodies[2].mass"
  int first_line = 0;   // 1-based
  int second_line = 0;  // 1-based

  // "given twice (lines A and B): remove one"
  std::string describe() const;
};

// The first key (in document order) that appears twice in one map of the tree, if any.
std::optional<DuplicateKey> findDuplicateKey(const YAML::Node& node);

}  // namespace rail::core
