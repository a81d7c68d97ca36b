// Track data (paper Tables 1 and 2 plus the sleeper and rail-seat geometry) and its YAML loader.
// SI units throughout; angles in rad.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include <rail_core/support_zone.hpp>

#include "rail_track_node/elements.hpp"

namespace rail {
namespace track {

/// Per-direction properties of a spring-damper family (paper Table 2). Directions are those of the
/// element frame: longitudinal (along the track), transversal (lateral), vertical (normal to the track
/// plane, or to the inclined rail seat for the pads).
struct SpringDamperData {
  Eigen::Vector3d k = Eigen::Vector3d::Zero();  ///< stiffness [longitudinal, transversal, vertical], N/m
  Eigen::Vector3d c = Eigen::Vector3d::Zero();  ///< damping [longitudinal, transversal, vertical], N s/m
  double k_roll = 0.0;  ///< rotational stiffness about the longitudinal axis, N m/rad (pads only, else 0)
  double mass = 0.0;    ///< lumped mass carried by the element's upper node, kg (ballast only, else 0)
};

/// Cross-track geometry of the rails and sleepers.
struct TrackLayout {
  double rail_lateral_offset = 0.0;   ///< lateral distance centre line -> rail centroid / rail seat, m
  double pad_thickness = 0.0;         ///< m
  double rail_centroid_height = 0.0;  ///< height of the rail centroid above the rail foot, m
  double rail_inclination = 0.0;      ///< rail cant towards the track centre, rad
  double sleeper_spacing = 0.0;       ///< m
  int rail_elements_between_sleepers = 6;
  double sleeper_length = 0.0;             ///< m
  double sleeper_height = 0.0;             ///< m (rail seat to sleeper bottom)
  double sleeper_inner_node_offset = 0.0;  ///< |y| of the two inner sleeper nodes, m
  std::vector<int> ballast_nodes;          ///< sleeper nodes (0..5, right to left) resting on the ballast

  /// Height of the rail centroid above the rail seat (pad thickness + centroid height), m.
  double railCentroidAboveSeat() const { return pad_thickness + rail_centroid_height; }
};

/// Wave-absorbing rail-end dashpots (see absorbingEndDashpots).
struct AbsorbingEnds {
  bool enabled = false;
  double design_frequency = 0.0;  ///< Hz
};

/// Everything needed to mesh the track.
struct TrackData {
  BeamSection rail;
  BeamSection sleeper;
  SpringDamperData pad;
  SpringDamperData ballast;
  SpringDamperData sleeper_interaction;
  TrackLayout layout;
  AbsorbingEnds absorbing_ends;
  /// Pads and ballast scaled along the track (the scene's track.support, effects.support_variation);
  /// empty: every sleeper as the data say.
  std::vector<rail::core::SupportZone> support_zones;
};

/// Loads a track data file. Throws std::runtime_error("<file>: <key.path>: <what>, got <value>") on an
/// unknown key, a missing key, a value of the wrong type or a non-positive (non-physical) value.
TrackData loadTrackData(const std::string& path);

/// Same, from YAML text; source_name stands for the file name in messages.
TrackData parseTrackData(const std::string& yaml_text, const std::string& source_name);

/// Removes the track's own damping (effects.track_damping off): every Rayleigh coefficient of rails and
/// sleepers and every pad, ballast and sleeper-interaction damper. The absorbing ends are left as they are.
void removeTrackDamping(TrackData& data);

}  // namespace track
}  // namespace rail
