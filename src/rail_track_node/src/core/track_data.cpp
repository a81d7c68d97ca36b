#include "rail_track_node/track_data.hpp"

#include <yaml-cpp/yaml.h>

#include "rail_core/yaml_reader.hpp"

#include <set>
#include <stdexcept>

#include <rail_contact/format.hpp>

namespace rail {
namespace track {

using contact::formatNumber;

namespace {

using core::MapReader;

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
  r.finish();
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
  r.finish();
  return d;
}

TrackData readTrackData(const YAML::Node& root, const std::string& source_name);

}  // namespace

TrackData parseTrackData(const std::string& yaml_text, const std::string& source_name) {
  return readTrackData(core::parseYaml(yaml_text, source_name), source_name);
}

TrackData loadTrackData(const std::string& path) { return readTrackData(core::loadYamlFile(path), path); }

namespace {

// The track data of a parsed file.
TrackData readTrackData(const YAML::Node& root, const std::string& source_name) {
  MapReader r(root, "", source_name);
  TrackData data;
  data.rail = readBeam(r.map("rail"));
  data.sleeper = readBeam(r.map("sleeper"));
  data.pad = readSpring(r.map("pad"), true, false);
  data.ballast = readSpring(r.map("ballast"), false, true);
  data.sleeper_interaction = readSpring(r.map("sleeper_interaction"), false, false);

  MapReader g = r.map("layout");
  TrackLayout& L = data.layout;
  L.rail_lateral_offset = g.positive("rail_lateral_offset", kMaxTrackLength, "m");
  L.pad_thickness = g.positive("pad_thickness", kMaxSectionHeight, "m");
  L.rail_centroid_height = g.positive("rail_centroid_height", kMaxSectionHeight, "m");
  L.rail_inclination = g.nonNegative("rail_inclination", 0.5, "rad");
  L.sleeper_spacing = g.positive("sleeper_spacing", kMaxTrackLength, "m");
  L.rail_elements_between_sleepers = g.positiveInteger("rail_elements_between_sleepers", kMaxElementsBetweenSleepers);
  L.sleeper_length = g.positive("sleeper_length", kMaxTrackLength, "m");
  L.sleeper_height = g.positive("sleeper_height", kMaxSectionHeight, "m");
  L.sleeper_inner_node_offset = g.positive("sleeper_inner_node_offset", kMaxTrackLength, "m");
  L.ballast_nodes = g.integerList("ballast_nodes");
  if (L.rail_inclination >= 0.5)
    g.fail("rail_inclination", "must be a small angle in rad (below 0.5), got " + formatNumber(L.rail_inclination));
  if (!(L.rail_lateral_offset < 0.5 * L.sleeper_length))
    g.fail("rail_lateral_offset", "must be smaller than half of layout.sleeper_length (" +
                                      formatNumber(L.sleeper_length) + " / 2), got " +
                                      formatNumber(L.rail_lateral_offset));
  if (!(L.sleeper_inner_node_offset < L.rail_lateral_offset))
    g.fail("sleeper_inner_node_offset", "must be smaller than rail_lateral_offset (" +
                                            formatNumber(L.rail_lateral_offset) + "), got " +
                                            formatNumber(L.sleeper_inner_node_offset));
  if (L.ballast_nodes.empty()) g.fail("ballast_nodes", "must list at least one sleeper node, got []");
  std::set<int> seen;
  for (int n : L.ballast_nodes) {
    if (n < 0 || n > 5 || !seen.insert(n).second)
      g.fail("ballast_nodes", "entries must be distinct sleeper node indices 0..5, got " + std::to_string(n));
  }
  g.finish();

  MapReader a = r.map("absorbing_ends");
  data.absorbing_ends.enabled = a.boolean("enabled");
  data.absorbing_ends.design_frequency = a.positive("design_frequency", kMaxDesignFrequency, "Hz");
  a.finish();

  r.finish();
  return data;
}

}  // namespace

void removeTrackDamping(TrackData& data) {
  for (BeamSection* b : {&data.rail, &data.sleeper}) {
    b->rayleigh_alpha = 0.0;
    b->rayleigh_beta = 0.0;
  }
  for (SpringDamperData* s : {&data.pad, &data.ballast, &data.sleeper_interaction}) s->c.setZero();
}

}  // namespace track
}  // namespace rail
