// Scene -> flexible track (see scene_track.hpp).
#include "rail_track_node/scene_track.hpp"

#include <cmath>
#include <exception>
#include <string>
#include <utility>

#include <rail_contact/format.hpp>
#include <rail_core/geometry_builder.hpp>
#include <rail_core/scene_loader.hpp>

namespace rail {
namespace track {

namespace rc = rail::contact;
using rail::core::Scene;
using rail::core::SceneError;

TrackData sceneTrackData(const Scene& scene, const rc::GeometrySpec& geometry, const SceneTrackOptions& options) {
  TrackData data;
  try {
    data = loadTrackData(scene.track.data.path);
  } catch (const std::exception& e) {
    throw SceneError(scene.file + ": track.data: " + e.what());
  }
  if (!(options.rail_height > data.layout.rail_centroid_height))
    throw SceneError(scene.file + ": track.data: " + scene.track.data.path +
                     ": layout.rail_centroid_height: must lie below the rail height (" +
                     rc::formatNumber(options.rail_height) + " m), got " +
                     rc::formatNumber(data.layout.rail_centroid_height));
  TrackLayout& L = data.layout;
  L.sleeper_spacing = scene.track.sleeper_spacing;
  L.rail_elements_between_sleepers = scene.track.rail_elements_between_sleepers;
  L.rail_inclination = geometry.rail_inclination;
  L.rail_lateral_offset =
      geometry.rail_half_spacing + (L.pad_thickness + options.rail_height) * std::sin(L.rail_inclination);
  if (!(L.rail_lateral_offset < 0.5 * L.sleeper_length))
    throw SceneError(scene.file + ": track.gauge: the rail seats (" + rc::formatNumber(L.rail_lateral_offset) +
                     " m from the centre) lie beyond the sleeper ends (track.data: " + scene.track.data.path +
                     ": layout.sleeper_length " + rc::formatNumber(L.sleeper_length) + " m)");
  if (!scene.effects.track_damping) removeTrackDamping(data);
  data.absorbing_ends.enabled = scene.effects.absorbing_ends;
  if (scene.effects.support_variation) data.support_zones = scene.track.support;
  return data;
}

double seatPlaneBelowCentreLine(const TrackData& data, double rail_height) {
  return (data.layout.pad_thickness + rail_height) * std::cos(data.layout.rail_inclination);
}

TrackFrameFunction seatPlaneFrames(const rc::TrackGeometry& geometry, double seat_below_centre) {
  return [&geometry, seat_below_centre](double s) {
    rc::TrackPoint c;
    geometry.centre(s, c);
    TrackFrameSample F;
    F.R_track_to_world = c.R_track_to_world;
    F.p_centre_in_world = c.p_center_in_world - seat_below_centre * c.R_track_to_world.col(2);
    return F;
  };
}

TrackLine resolveTrackLine(const Scene& scene, const SceneTrackOptions& options) {
  rc::TrackGeometry geometry = rail::core::buildTrackGeometry(scene);
  TrackData data = sceneTrackData(scene, geometry.spec(), options);
  return TrackLine{scene.file,           std::move(geometry), std::move(data),   scene.track.start_arc_length,
                   scene.track.length(), options.rail_height, options.g_in_world};
}

SceneTrack buildSceneTrack(TrackLine line) {
  const double seat = seatPlaneBelowCentreLine(line.data, line.rail_height);
  MeshOptions mesh;
  mesh.s_start = line.s_start;
  mesh.track_length = line.length;
  TrackModel model;
  try {
    model = buildTrackModel(line.data, mesh, seatPlaneFrames(line.geometry, seat), line.g_in_world);
  } catch (const SceneError&) {
    throw;
  } catch (const std::exception& e) {
    throw SceneError(line.source + ": track: " + e.what());
  }
  return SceneTrack{std::move(line.geometry), std::move(model), seat, line.rail_height};
}

SceneTrack buildSceneTrack(const Scene& scene, const SceneTrackOptions& options) {
  return buildSceneTrack(resolveTrackLine(scene, options));
}

}  // namespace track
}  // namespace rail
