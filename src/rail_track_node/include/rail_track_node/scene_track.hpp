// The flexible track of a scene: rail_contact track geometry (centre line, rails) + the FE track data
// with the scene applied + the FE mesh generated on the geometry's centre-line frames + the assembled
// model. Built once at start-up; constant afterwards. ROS-free.
//
// Vertical placement: the geometry's centre line lies at the level of the rail profile origins (top of
// the rail heads, rail_vertical_offset 0); the FE mesh wants the plane of the rail seats, which lies
// (pad_thickness + rail_height) cos(inclination) below it along the track normal. Laterally the FE rail
// seat is put where the inclined rail axis through the geometry's profile origin meets the seat plane,
// so the FE rails run under the geometry's rails.
#pragma once

#include <string>

#include <Eigen/Core>

#include <rail_contact/profile.hpp>
#include <rail_contact/track_geometry.hpp>
#include <rail_core/scene.hpp>

#include "rail_track_node/track_data.hpp"
#include "rail_track_node/track_mesh.hpp"
#include "rail_track_node/track_model.hpp"

namespace rail {
namespace track {

/// Build options that the scene does not hold.
struct SceneTrackOptions {
  /// Rail height, foot to head top (m); the track data file has the centroid height only. 60E1 value
  /// (EN 13674-1), the rail of the built-in profile.
  double rail_height = rail::contact::uic60::kHeight;
  Eigen::Vector3d g_in_world = Eigen::Vector3d(0.0, 0.0, -9.81);  ///< gravity, m/s^2
};

/// Track data of the scene: the scene's track.data file with the scene's choices applied:
///  - layout: sleeper_spacing, rail_elements_between_sleepers, rail_inclination = atan(scene ratio) and
///    rail_lateral_offset = rail_half_spacing + (pad_thickness + rail_height) sin(inclination) from the
///    geometry spec (the scene's values win over the file's);
///  - effects.track_damping off: every Rayleigh coefficient and every pad / ballast / interaction damper
///    is zero, so C is assembled with no entry;
///  - effects.absorbing_ends decides absorbing_ends.enabled (off: no end dashpots are built).
/// Throws rail::core::SceneError naming the scene file and track.data.
TrackData sceneTrackData(const rail::core::Scene& scene, const rail::contact::GeometrySpec& geometry,
                         const SceneTrackOptions& options = {});

/// Distance (m) from the geometry's centre line down to the FE rail-seat plane, along the track normal.
double seatPlaneBelowCentreLine(const TrackData& data, double rail_height);

/// Centre-line frames of the FE mesh: the geometry's (design) track frame at s, its point moved down
/// along the track normal to the rail-seat plane. geometry must outlive the returned function (build
/// time only).
TrackFrameFunction seatPlaneFrames(const rail::contact::TrackGeometry& geometry, double seat_below_centre);

/// The line a flexible track is built on, resolved once from a scene and constant afterwards: what the
/// full-length track and the track window take instead of the Scene.
struct TrackLine {
  std::string source;                                    ///< the scene file; build errors start with it
  rail::contact::TrackGeometry geometry;                 ///< design geometry (+ irregularities when on)
  TrackData data;                                        ///< sceneTrackData: the track data file with the scene applied
  double s_start = 0.0;                                  ///< m, track.start_arc_length
  double length = 0.0;                                   ///< m, the line's length (track end - start)
  double rail_height = 0.0;                              ///< m, foot to head top
  Eigen::Vector3d g_in_world = Eigen::Vector3d::Zero();  ///< gravity, m/s^2
};

/// Resolves the scene's line: geometry (rail_core::buildTrackGeometry), data (sceneTrackData), extent.
/// Throws rail::core::SceneError.
TrackLine resolveTrackLine(const rail::core::Scene& scene, const SceneTrackOptions& options = {});

/// Everything built from a scene for the flexible track. Not to be moved once an integrator refers to
/// model.system.
struct SceneTrack {
  rail::contact::TrackGeometry geometry;  ///< design geometry (+ irregularities when on)
  TrackModel model;                       ///< FE data (scene applied), mesh and M, C, K, f_g
  double seat_below_centre = 0.0;         ///< m, see seatPlaneBelowCentreLine
  double rail_height = 0.0;               ///< m, foot to head top
};

/// Builds the line's track: mesh over [s_start, s_start + length] on seatPlaneFrames, model. Throws
/// rail::core::SceneError naming line.source.
SceneTrack buildSceneTrack(TrackLine line);
/// buildSceneTrack(resolveTrackLine(scene, options)).
SceneTrack buildSceneTrack(const rail::core::Scene& scene, const SceneTrackOptions& options = {});

}  // namespace track
}  // namespace rail
