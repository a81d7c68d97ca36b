#include "rail_track_node/track_data.hpp"

#include <yaml-cpp/yaml.h>

#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

namespace rail {
namespace track {

namespace {

std::string describe(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing";
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list";
  return "a map";
}

std::string fmt(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

// A YAML map being read: remembers the keys consumed to reject unknown ones.
class MapReader {
 public:
  MapReader(const YAML::Node& node, std::string path, const std::string& file)
      : node_(node), path_(std::move(path)), file_(file) {
    if (!node_.IsMap()) fail(path_.empty() ? "(root)" : path_, "expected a map", describe(node_));
  }

  [[noreturn]] void fail(const std::string& key_path, const std::string& what, const std::string& got) const {
    throw std::runtime_error(file_ + ": " + key_path + ": " + what + ", got " + got);
  }

  std::string keyPath(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  YAML::Node get(const std::string& key) {
    const YAML::Node v = node_[key];
    if (!v.IsDefined()) fail(keyPath(key), "missing key", "nothing");
    used_.insert(key);
    return v;
  }

  double number(const std::string& key) {
    const YAML::Node v = get(key);
    if (!v.IsScalar()) fail(keyPath(key), "expected a number", describe(v));
    try {
      return v.as<double>();
    } catch (const YAML::Exception&) {
      fail(keyPath(key), "expected a number", describe(v));
    }
  }

  double positive(const std::string& key) {
    const double x = number(key);
    if (!(x > 0.0)) fail(keyPath(key), "must be positive", fmt(x));
    return x;
  }

  double nonNegative(const std::string& key) {
    const double x = number(key);
    if (!(x >= 0.0)) fail(keyPath(key), "must not be negative", fmt(x));
    return x;
  }

  int positiveInt(const std::string& key) {
    const YAML::Node v = get(key);
    int x = 0;
    try {
      if (!v.IsScalar()) throw YAML::Exception(YAML::Mark::null_mark(), "");
      x = v.as<int>();
    } catch (const YAML::Exception&) {
      fail(keyPath(key), "expected an integer", describe(v));
    }
    if (x <= 0) fail(keyPath(key), "must be positive", std::to_string(x));
    return x;
  }

  bool boolean(const std::string& key) {
    const YAML::Node v = get(key);
    try {
      if (!v.IsScalar()) throw YAML::Exception(YAML::Mark::null_mark(), "");
      return v.as<bool>();
    } catch (const YAML::Exception&) {
      fail(keyPath(key), "expected true or false", describe(v));
    }
  }

  std::vector<int> intList(const std::string& key) {
    const YAML::Node v = get(key);
    if (!v.IsSequence()) fail(keyPath(key), "expected a list of integers", describe(v));
    std::vector<int> out;
    for (std::size_t i = 0; i < v.size(); ++i) {
      try {
        if (!v[i].IsScalar()) throw YAML::Exception(YAML::Mark::null_mark(), "");
        out.push_back(v[i].as<int>());
      } catch (const YAML::Exception&) {
        fail(keyPath(key) + "[" + std::to_string(i) + "]", "expected an integer", describe(v[i]));
      }
    }
    return out;
  }

  MapReader child(const std::string& key) { return MapReader(get(key), keyPath(key), file_); }

  // Throws on the first key that was never read.
  void rejectUnknownKeys() const {
    for (const auto& kv : node_) {
      const std::string key = kv.first.as<std::string>();
      if (!used_.count(key)) fail(path_.empty() ? "(root)" : path_, "unknown key", "'" + key + "'");
    }
  }

  const std::string& path() const { return path_; }

 private:
  YAML::Node node_;
  std::string path_;
  const std::string& file_;
  std::set<std::string> used_;
};

BeamSection readBeam(MapReader r) {
  BeamSection s;
  s.E = r.positive("E");
  s.G = r.positive("G");
  s.A = r.positive("A");
  s.J = r.positive("J");
  s.I_y = r.positive("I_y");
  s.I_z = r.positive("I_z");
  s.rho = r.positive("rho");
  s.rayleigh_alpha = r.nonNegative("rayleigh_alpha");
  s.rayleigh_beta = r.nonNegative("rayleigh_beta");
  r.rejectUnknownKeys();
  return s;
}

SpringDamperData readSpring(MapReader r, bool has_roll, bool has_mass) {
  SpringDamperData d;
  d.k = Eigen::Vector3d(r.positive("k_longitudinal"), r.positive("k_transversal"), r.positive("k_vertical"));
  d.c = Eigen::Vector3d(r.positive("c_longitudinal"), r.positive("c_transversal"), r.positive("c_vertical"));
  if (has_roll) d.k_roll = r.positive("k_roll");
  if (has_mass) d.mass = r.positive("mass");
  r.rejectUnknownKeys();
  return d;
}

}  // namespace

TrackData parseTrackData(const std::string& yaml_text, const std::string& source_name) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(source_name + ":" + std::to_string(e.mark.line + 1) + ": YAML syntax error: " + e.msg);
  }
  MapReader r(root, "", source_name);
  TrackData data;
  data.rail = readBeam(r.child("rail"));
  data.sleeper = readBeam(r.child("sleeper"));
  data.pad = readSpring(r.child("pad"), true, false);
  data.ballast = readSpring(r.child("ballast"), false, true);
  data.sleeper_interaction = readSpring(r.child("sleeper_interaction"), false, false);

  MapReader g = r.child("layout");
  TrackLayout& L = data.layout;
  L.rail_lateral_offset = g.positive("rail_lateral_offset");
  L.pad_thickness = g.positive("pad_thickness");
  L.rail_centroid_height = g.positive("rail_centroid_height");
  L.rail_inclination = g.nonNegative("rail_inclination");
  L.sleeper_spacing = g.positive("sleeper_spacing");
  L.rail_elements_between_sleepers = g.positiveInt("rail_elements_between_sleepers");
  L.sleeper_length = g.positive("sleeper_length");
  L.sleeper_height = g.positive("sleeper_height");
  L.sleeper_inner_node_offset = g.positive("sleeper_inner_node_offset");
  L.ballast_nodes = g.intList("ballast_nodes");
  if (L.rail_inclination >= 0.5)
    g.fail(g.keyPath("rail_inclination"), "must be a small angle in rad (below 0.5)", fmt(L.rail_inclination));
  if (!(L.rail_lateral_offset < 0.5 * L.sleeper_length))
    g.fail(g.keyPath("rail_lateral_offset"),
           "must be smaller than half the sleeper length (" + fmt(0.5 * L.sleeper_length) + ")",
           fmt(L.rail_lateral_offset));
  if (!(L.sleeper_inner_node_offset < L.rail_lateral_offset))
    g.fail(g.keyPath("sleeper_inner_node_offset"),
           "must be smaller than rail_lateral_offset (" + fmt(L.rail_lateral_offset) + ")",
           fmt(L.sleeper_inner_node_offset));
  if (L.ballast_nodes.empty()) g.fail(g.keyPath("ballast_nodes"), "must list at least one sleeper node", "[]");
  std::set<int> seen;
  for (int n : L.ballast_nodes) {
    if (n < 0 || n > 5 || !seen.insert(n).second)
      g.fail(g.keyPath("ballast_nodes"), "entries must be distinct sleeper node indices 0..5", std::to_string(n));
  }
  g.rejectUnknownKeys();

  MapReader a = r.child("absorbing_ends");
  data.absorbing_ends.enabled = a.boolean("enabled");
  data.absorbing_ends.design_frequency = a.positive("design_frequency");
  a.rejectUnknownKeys();

  r.rejectUnknownKeys();
  return data;
}

TrackData loadTrackData(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parseTrackData(ss.str(), path);
}

}  // namespace track
}  // namespace rail
