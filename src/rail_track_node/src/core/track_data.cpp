#include "rail_track_node/track_data.hpp"

#include <yaml-cpp/yaml.h>

#include "rail_core/yaml_duplicates.hpp"

#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include <rail_contact/format.hpp>

namespace rail {
namespace track {

using contact::formatNumber;

namespace {

std::string describe(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing";
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list";
  return "a map";
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

  // A number in (0, max]; max is the physical upper bound of the quantity, given with its unit. Values
  // above it (and inf) are refused, never clamped.
  double positive(const std::string& key, double max, const char* unit) {
    const double x = number(key);
    if (!(x > 0.0)) fail(keyPath(key), "must be positive", formatNumber(x));
    if (!(x <= max)) fail(keyPath(key), "must be at most " + formatNumber(max) + " " + unit, formatNumber(x));
    return x;
  }

  // A number in [0, max], as positive().
  double nonNegative(const std::string& key, double max, const char* unit) {
    const double x = number(key);
    if (!(x >= 0.0)) fail(keyPath(key), "must not be negative", formatNumber(x));
    if (!(x <= max)) fail(keyPath(key), "must be at most " + formatNumber(max) + " " + unit, formatNumber(x));
    return x;
  }

  // An integer in [1, max].
  int positiveInt(const std::string& key, int max) {
    const YAML::Node v = get(key);
    int x = 0;
    try {
      if (!v.IsScalar()) throw YAML::Exception(YAML::Mark::null_mark(), "");
      x = v.as<int>();
    } catch (const YAML::Exception&) {
      fail(keyPath(key), "expected an integer", describe(v));
    }
    if (x <= 0) fail(keyPath(key), "must be positive", std::to_string(x));
    if (x > max) fail(keyPath(key), "must be at most " + std::to_string(max), std::to_string(x));
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

// Upper bounds of the track data, refused above (inf included). They are far beyond any real track
// component, so they only catch mistyped or corrupted values before they reach the FE model.
constexpr double kMaxModulus = 1e13;       // Pa, E and G (diamond: E = 1.2e12 Pa)
constexpr double kMaxArea = 1.0;           // m^2, beam cross-section (a 1 m x 1 m section)
constexpr double kMaxSecondMoment = 1.0;   // m^4, J, I_y, I_z (1 m x 1 m section: I = 0.083 m^4)
constexpr double kMaxDensity = 1e5;        // kg/m^3 (densest element, osmium: 2.26e4)
constexpr double kMaxRayleighAlpha = 1e4;  // 1/s, mass-proportional damping coefficient
constexpr double kMaxRayleighBeta = 10.0;  // s, stiffness-proportional damping coefficient
constexpr double kMaxStiffness = 1e12;     // N/m (translational) and N m/rad (k_roll)
constexpr double kMaxDamping = 1e12;       // N s/m
constexpr double kMaxLumpedMass = 1e5;     // kg, ballast mass per sleeper node
constexpr double kMaxTrackLength = 10.0;   // m, sleeper spacing / length, rail lateral offset
constexpr double kMaxSectionHeight = 2.0;  // m, pad thickness, rail centroid height, sleeper height
constexpr int kMaxElementsBetweenSleepers = 1000;
constexpr double kMaxDesignFrequency = 1e5;  // Hz, absorbing-end tuning frequency

BeamSection readBeam(MapReader r) {
  BeamSection s;
  s.E = r.positive("E", kMaxModulus, "Pa");
  s.G = r.positive("G", kMaxModulus, "Pa");
  s.A = r.positive("A", kMaxArea, "m^2");
  s.J = r.positive("J", kMaxSecondMoment, "m^4");
  s.I_y = r.positive("I_y", kMaxSecondMoment, "m^4");
  s.I_z = r.positive("I_z", kMaxSecondMoment, "m^4");
  s.rho = r.positive("rho", kMaxDensity, "kg/m^3");
  s.rayleigh_alpha = r.nonNegative("rayleigh_alpha", kMaxRayleighAlpha, "1/s");
  s.rayleigh_beta = r.nonNegative("rayleigh_beta", kMaxRayleighBeta, "s");
  r.rejectUnknownKeys();
  return s;
}

SpringDamperData readSpring(MapReader r, bool has_roll, bool has_mass) {
  SpringDamperData d;
  d.k = Eigen::Vector3d(r.positive("k_longitudinal", kMaxStiffness, "N/m"),
                        r.positive("k_transversal", kMaxStiffness, "N/m"),
                        r.positive("k_vertical", kMaxStiffness, "N/m"));
  d.c = Eigen::Vector3d(r.positive("c_longitudinal", kMaxDamping, "N s/m"),
                        r.positive("c_transversal", kMaxDamping, "N s/m"),
                        r.positive("c_vertical", kMaxDamping, "N s/m"));
  if (has_roll) d.k_roll = r.positive("k_roll", kMaxStiffness, "N m/rad");
  if (has_mass) d.mass = r.positive("mass", kMaxLumpedMass, "kg");
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
  if (const auto dup = core::findDuplicateKey(root)) {
    throw std::runtime_error(source_name + ": " + dup->field + ": " + dup->describe());
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
  L.rail_lateral_offset = g.positive("rail_lateral_offset", kMaxTrackLength, "m");
  L.pad_thickness = g.positive("pad_thickness", kMaxSectionHeight, "m");
  L.rail_centroid_height = g.positive("rail_centroid_height", kMaxSectionHeight, "m");
  L.rail_inclination = g.nonNegative("rail_inclination", 0.5, "rad");
  L.sleeper_spacing = g.positive("sleeper_spacing", kMaxTrackLength, "m");
  L.rail_elements_between_sleepers = g.positiveInt("rail_elements_between_sleepers", kMaxElementsBetweenSleepers);
  L.sleeper_length = g.positive("sleeper_length", kMaxTrackLength, "m");
  L.sleeper_height = g.positive("sleeper_height", kMaxSectionHeight, "m");
  L.sleeper_inner_node_offset = g.positive("sleeper_inner_node_offset", kMaxTrackLength, "m");
  L.ballast_nodes = g.intList("ballast_nodes");
  if (L.rail_inclination >= 0.5)
    g.fail(g.keyPath("rail_inclination"), "must be a small angle in rad (below 0.5)", formatNumber(L.rail_inclination));
  if (!(L.rail_lateral_offset < 0.5 * L.sleeper_length))
    g.fail(g.keyPath("rail_lateral_offset"),
           "must be smaller than half of layout.sleeper_length (" + formatNumber(L.sleeper_length) + " / 2)",
           formatNumber(L.rail_lateral_offset));
  if (!(L.sleeper_inner_node_offset < L.rail_lateral_offset))
    g.fail(g.keyPath("sleeper_inner_node_offset"),
           "must be smaller than rail_lateral_offset (" + formatNumber(L.rail_lateral_offset) + ")",
           formatNumber(L.sleeper_inner_node_offset));
  if (L.ballast_nodes.empty()) g.fail(g.keyPath("ballast_nodes"), "must list at least one sleeper node", "[]");
  std::set<int> seen;
  for (int n : L.ballast_nodes) {
    if (n < 0 || n > 5 || !seen.insert(n).second)
      g.fail(g.keyPath("ballast_nodes"), "entries must be distinct sleeper node indices 0..5", std::to_string(n));
  }
  g.rejectUnknownKeys();

  MapReader a = r.child("absorbing_ends");
  data.absorbing_ends.enabled = a.boolean("enabled");
  data.absorbing_ends.design_frequency = a.positive("design_frequency", kMaxDesignFrequency, "Hz");
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

void removeTrackDamping(TrackData& data) {
  for (BeamSection* b : {&data.rail, &data.sleeper}) {
    b->rayleigh_alpha = 0.0;
    b->rayleigh_beta = 0.0;
  }
  for (SpringDamperData* s : {&data.pad, &data.ballast, &data.sleeper_interaction}) s->c.setZero();
}

}  // namespace track
}  // namespace rail
