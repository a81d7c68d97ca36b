#include "rail_core/yaml_duplicates.hpp"

#include <map>

namespace rail::core {

namespace {

std::optional<DuplicateKey> findIn(const YAML::Node& node, const std::string& path) {
  if (node.IsMap()) {
    std::map<std::string, int> line_of_key;
    for (const auto& kv : node) {
      const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : std::string();
      const int line = kv.first.Mark().line + 1;
      const std::string field = path.empty() ? key : path + "." + key;
      const auto it = line_of_key.find(key);
      if (it != line_of_key.end()) return DuplicateKey{field, it->second, line};
      line_of_key.emplace(key, line);
      if (auto inner = findIn(kv.second, field)) return inner;
    }
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) {
      if (auto inner = findIn(node[i], path + "[" + std::to_string(i) + "]")) return inner;
    }
  }
  return std::nullopt;
}

}  // namespace

std::string DuplicateKey::describe() const {
  return "given twice (lines " + std::to_string(first_line) + " and " + std::to_string(second_line) + "): remove one";
}

std::optional<DuplicateKey> findDuplicateKey(const YAML::Node& node) { return findIn(node, ""); }

}  // namespace rail::core
